"""04 — A COLMAP reconstruction in: import it and adjust it with control.

COLMAP writes a reconstruction as three text files: ``cameras.txt`` (the intrinsics in
pixels), ``images.txt`` (one world → camera pose per image as a quaternion and a
translation, then the measured 2-D points) and ``points3D.txt`` (the points with their
tracks). This example writes such a reconstruction itself — four images of a drone flight 100 m
over a field, 0.5 px of measuring noise, the poses and points as a reconstruction would
leave them (a little off) — into a temporary folder, then imports it with
:func:`orientviz.read_colmap`.

The import turns COLMAP's conventions into orientviz's (R image → object, image y up,
mm with a nominal pixel size of 10 µm); the first check is that the imported projection
centres are the ones written. COLMAP has no control points, so the block has no datum:
four of its points get their known coordinates (fixed control) and the bundle
adjustment then fits the block to them.

Run: ``python examples/04_colmap_import.py``
"""

import tempfile
from pathlib import Path

import numpy as np

import orientviz as ov

FLIP = np.diag([1.0, -1.0, -1.0])  # orientviz camera frame (y up, looking along −z) ↔ COLMAP's


def quaternion_from_matrix(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation matrix, w ≥ 0 (COLMAP's order)."""
    w = np.sqrt(max(0.0, 1.0 + np.trace(R))) / 2.0
    if w > 1e-6:
        x = (R[2, 1] - R[1, 2]) / (4 * w)
        y = (R[0, 2] - R[2, 0]) / (4 * w)
        z = (R[1, 0] - R[0, 1]) / (4 * w)
        return np.array([w, x, y, z])
    # a half turn: take the axis from the largest diagonal element
    k = int(np.argmax(np.diag(R)))
    q = np.zeros(4)
    q[1 + k] = np.sqrt(max(0.0, 1.0 + 2 * R[k, k] - np.trace(R))) / 2.0
    i, j = (k + 1) % 3, (k + 2) % 3
    q[0] = (R[j, i] - R[i, j]) / (4 * q[1 + k])
    q[1 + i] = (R[i, k] + R[k, i]) / (4 * q[1 + k])
    q[1 + j] = (R[j, k] + R[k, j]) / (4 * q[1 + k])
    return q if q[0] >= 0 else -q


def write_reconstruction(folder: Path, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Write a small COLMAP reconstruction (text format).

    Returns the projection centres as written (4, 3) and the true points (60, 3), in m.
    """
    f, width, height = 1500.0, 2000, 1500  # focal length and image size in pixels
    cx, cy = width / 2, height / 2
    X0 = np.array([[0.0, 0.0, 100.0], [30.0, 1.0, 101.0], [60.0, -1.0, 99.0], [90.0, 0.5, 100.0]])
    angles = ov.to_rad(
        np.array([[0.5, -0.3, 1.0], [-0.4, 0.6, -0.8], [0.3, 0.2, 0.5], [-0.2, -0.5, 0.0]]), "gon"
    )
    points = np.column_stack(
        [rng.uniform(-20.0, 110.0, 60), rng.uniform(-35.0, 35.0, 60), rng.uniform(0.0, 5.0, 60)]
    )

    tracks: dict[int, list[tuple[int, int]]] = {k: [] for k in range(len(points))}
    written = np.empty_like(X0)
    lines = [
        "# IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME",
        "#   POINTS2D[] as (X, Y, POINT3D_ID)",
    ]
    for i in range(len(X0)):
        R_cw = FLIP @ ov.matrix_from_opk(*angles[i]).T  # world → camera, COLMAP's frame
        t = -R_cw @ X0[i]
        cam = points @ R_cw.T + t  # camera coordinates, z forward
        uv = f * cam[:, :2] / cam[:, 2:] + [cx, cy] + rng.normal(0.0, 0.5, (len(points), 2))
        seen = np.flatnonzero(
            (uv[:, 0] > 0) & (uv[:, 0] < width) & (uv[:, 1] > 0) & (uv[:, 1] < height)
        )
        # the pose as a reconstruction leaves it: a few cm and a few mgon off
        R_rec = ov.matrix_from_opk(*rng.normal(0.0, 2e-4, 3)) @ R_cw
        written[i] = X0[i] + rng.normal(0.0, 0.05, 3)
        t_rec = -R_rec @ written[i]
        q = quaternion_from_matrix(R_rec)
        lines.append(
            f"{i + 1} {' '.join(f'{v:.12f}' for v in q)} {' '.join(f'{v:.6f}' for v in t_rec)} 1 img{i + 1}.jpg"
        )
        lines.append(" ".join(f"{uv[k, 0]:.3f} {uv[k, 1]:.3f} {k + 1}" for k in seen))
        for idx, k in enumerate(seen):
            tracks[k].append((i + 1, idx))
    (folder / "images.txt").write_text("\n".join(lines) + "\n")
    (folder / "cameras.txt").write_text(f"1 SIMPLE_PINHOLE {width} {height} {f} {cx} {cy}\n")

    rows = []
    for k, track in tracks.items():
        if len(track) >= 2:  # COLMAP keeps points seen in two images or more
            xyz = points[k] + rng.normal(0.0, 0.05, 3)
            pairs = " ".join(f"{i} {j}" for i, j in track)
            rows.append(f"{k + 1} {xyz[0]:.4f} {xyz[1]:.4f} {xyz[2]:.4f} 128 128 128 0.5 {pairs}")
    (folder / "points3D.txt").write_text("\n".join(rows) + "\n")
    return written, points


def main() -> None:
    rng = np.random.default_rng(4)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        X0_written, points_true = write_reconstruction(folder, rng)
        print("wrote", ", ".join(sorted(p.name for p in folder.iterdir())))
        block = ov.read_colmap(folder, pixel_size_mm=0.01, sigma_px=0.5)

    print(block.summary())
    c = block.cameras.c[0]
    print(f"principal distance c = {c:.2f} mm (1500 px × 0.01 mm)")
    d = np.abs(block.images.X0 - X0_written).max()
    print(f"imported centres − written centres: largest {d * 1000:.4f} mm")
    v = block.residuals()  # image residuals at the imported values, mm
    print(f"reprojection RMS before the adjustment: {np.sqrt(np.mean(v**2)) / 0.01:.2f} px")

    # the datum: four points near the corners of the field become fixed control
    truth = points_true[[int(i) - 1 for i in block.points.ids]]  # point ids are COLMAP's
    xy = truth[:, :2]
    corners = [
        int(np.argmin(np.hypot(*(xy - corner).T)))
        for corner in ([-20, -35], [-20, 35], [110, -35], [110, 35])
    ]
    block.points.role[corners] = ov.CONTROL
    block.points.xyz_known[corners] = truth[corners]
    block.points.sigma[corners] = 0.0  # fixed

    adj = ov.bundle_adjust(block)
    print(adj.summary())
    xyz = adj.points
    tie = block.points.role == ov.TIE
    rms = np.sqrt(np.mean((xyz - truth)[tie] ** 2, axis=0))
    print(f"tie points vs the truth, RMS: X {rms[0]:.3f}  Y {rms[1]:.3f}  Z {rms[2]:.3f} m")
    print(f"sigma0 = {adj.sigma0:.3f}  redundancy = {adj.redundancy}")


if __name__ == "__main__":
    main()
