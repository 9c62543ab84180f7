"""orientviz's COLMAP text reader as it was before the streaming rewrite (commit 775b17c).

Kept verbatim (reading part only) as the baseline of ``bench_colmap_import.py``: it reads
every keypoint of images.txt in Python and the file twice. Not used by orientviz.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from orientviz.block import Block
from orientviz.errors import InputError
from orientviz.rotation import opk_from_matrix

FLIP = np.diag([1.0, -1.0, -1.0])

#: COLMAP camera models understood here: name → parameter names.
CAMERA_MODELS: dict[str, tuple[str, ...]] = {
    "SIMPLE_PINHOLE": ("f", "cx", "cy"),
    "PINHOLE": ("fx", "fy", "cx", "cy"),
    "SIMPLE_RADIAL": ("f", "cx", "cy", "k"),
    "RADIAL": ("f", "cx", "cy", "k1", "k2"),
    "OPENCV": ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"),
}


@dataclass
class _Camera:
    model: str
    width: int
    height: int
    params: NDArray[np.float64]

    def focal(self) -> float:
        p = dict(zip(CAMERA_MODELS[self.model], self.params))
        return float(p.get("f", 0.5 * (p.get("fx", 0.0) + p.get("fy", 0.0))))

    def principal_point(self) -> tuple[float, float]:
        p = dict(zip(CAMERA_MODELS[self.model], self.params))
        return float(p["cx"]), float(p["cy"])

    def distortion(self) -> tuple[float, float, float, float]:
        """k1, k2, p1, p2 (zeros where the model has none)."""
        p = dict(zip(CAMERA_MODELS[self.model], self.params))
        return (p.get("k", p.get("k1", 0.0)), p.get("k2", 0.0), p.get("p1", 0.0), p.get("p2", 0.0))


def _lines(path: Path):
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError("file not found", source=str(path)) from None
    except UnicodeDecodeError as exc:
        raise InputError(f"not a text file ({exc.reason})", source=str(path)) from None
    for no, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        if s and not s.startswith("#"):
            yield no, s


def _numbers(path: Path, no: int, fields: list[str], kinds: str, what: str) -> list:
    if len(fields) < len(kinds):
        raise InputError(
            f"expected {what} with {len(kinds)} fields, got {len(fields)}",
            source=str(path),
            where=f"line {no}",
        )
    out = []
    for i, (f, k) in enumerate(zip(fields, kinds)):
        try:
            v = int(f) if k == "i" else float(f) if k == "f" else f
        except ValueError:
            raise InputError(
                f"field {i + 1} of {what}: expected {'an integer' if k == 'i' else 'a number'}, "
                f"got {f!r}",
                source=str(path),
                where=f"line {no}",
            ) from None
        if k == "f" and not np.isfinite(v):
            raise InputError(
                f"field {i + 1} of {what}: expected a finite number, got {f!r}",
                source=str(path),
                where=f"line {no}",
            )
        out.append(v)
    return out


def _read_cameras(path: Path) -> dict[int, _Camera]:
    cams: dict[int, _Camera] = {}
    for no, line in _lines(path):
        f = line.split()
        cid, model, w, h = _numbers(path, no, f, "isii", "a camera")
        if model not in CAMERA_MODELS:
            raise InputError(
                f"camera model {model!r} is not supported (supported: {', '.join(CAMERA_MODELS)})",
                source=str(path),
                where=f"line {no}",
            )
        names = CAMERA_MODELS[model]
        params = _numbers(path, no, f[4:], "f" * len(names), f"{model} parameters")
        if len(f) - 4 != len(names):
            raise InputError(
                f"{model} has {len(names)} parameters, got {len(f) - 4}",
                source=str(path),
                where=f"line {no}",
            )
        if cid in cams:
            raise InputError(f"duplicate camera id {cid}", source=str(path), where=f"line {no}")
        cams[cid] = _Camera(model, w, h, np.array(params))
    if not cams:
        raise InputError("no cameras in the file", source=str(path), where=_end(path))
    return cams


def _end(path: Path) -> str:
    """``"line N"`` of the last line of an existing text file (for "nothing found" errors)."""
    try:
        n = len(path.read_text(encoding="utf-8").splitlines())
    except (OSError, UnicodeDecodeError):
        n = 0
    return f"line {max(n, 1)}"


def _read_points(path: Path) -> tuple[list[int], list[list[float]], list[tuple[int, list[int]]]]:
    """POINT3D_ID, X, Y, Z and the TRACK image ids (with the line number) of points3D.txt."""
    pid: list[int] = []
    xyz: list[list[float]] = []
    tracks: list[tuple[int, list[int]]] = []
    seen: set[int] = set()
    for no, line in _lines(path):
        f = line.split()
        vals = _numbers(path, no, f, "ifff", "a 3D point")
        if vals[0] in seen:
            raise InputError(
                f"duplicate POINT3D_ID {vals[0]}", source=str(path), where=f"line {no}"
            )
        seen.add(vals[0])
        track = f[8:]
        if len(track) % 2:
            raise InputError(
                f"expected TRACK[] as pairs IMAGE_ID POINT2D_IDX, got {len(track)} fields",
                source=str(path),
                where=f"line {no}",
            )
        ids = _numbers(path, no, track, "i" * len(track), "the TRACK") if track else []
        pid.append(vals[0])
        xyz.append(vals[1:4])
        tracks.append((no, ids[0::2]))
    return pid, xyz, tracks


def _undistort(cam: _Camera, uv: NDArray[np.float64]) -> NDArray[np.float64]:
    """Remove COLMAP's radial/tangential distortion from pixel coordinates."""
    k1, k2, p1, p2 = cam.distortion()
    if k1 == k2 == p1 == p2 == 0.0:
        return uv
    p = dict(zip(CAMERA_MODELS[cam.model], cam.params))
    fx = p.get("fx", p.get("f"))
    fy = p.get("fy", p.get("f"))
    cx, cy = cam.principal_point()
    d = np.column_stack([(uv[:, 0] - cx) / fx, (uv[:, 1] - cy) / fy])
    u = d.copy()
    for _ in range(20):  # fixed-point inversion of x_d = x (1 + k1 r² + k2 r⁴) + tangential
        x, y = u[:, 0], u[:, 1]
        r2 = x * x + y * y
        radial = k1 * r2 + k2 * r2 * r2
        dx = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        dy = y * radial + 2 * p2 * x * y + p1 * (r2 + 2 * y * y)
        u = d - np.column_stack([dx, dy])
    return np.column_stack([u[:, 0] * fx + cx, u[:, 1] * fy + cy])


def read_colmap(
    directory: str | Path,
    *,
    pixel_size_mm: float = 0.01,
    sigma_px: float = 1.0,
    sequence: str = "opk",
) -> Block:
    """Read a COLMAP text model into a Block.

    Parameters
    ----------
    directory : str or Path
        Folder with ``cameras.txt``, ``images.txt`` and ``points3D.txt``.
    pixel_size_mm : float, default 0.01
        Nominal pixel size in mm used to express image coordinates in mm.
    sigma_px : float, default 1.0
        A-priori σ of the image coordinates in pixels.
    sequence : {"opk", "pok"}
        Rotation sequence for the returned angles.

    Returns
    -------
    Block
        All points as tie points (COLMAP has no control); object units are COLMAP's.
    """
    d = Path(directory)
    if not d.is_dir():
        raise InputError(
            "expected a directory with cameras.txt, images.txt, points3D.txt", source=str(d)
        )
    cams = _read_cameras(d / "cameras.txt")
    cam_ids = sorted(cams)
    cam_index = {c: i for i, c in enumerate(cam_ids)}

    pts_path = d / "points3D.txt"
    pid, xyz, tracks = _read_points(pts_path)
    p_index = {p: i for i, p in enumerate(pid)}

    img_path = d / "images.txt"
    lines = list(_lines(img_path))
    # images.txt: two lines per image; the second (the 2D points) may be empty, which the
    # comment-stripping reader drops, so read by position in the raw text instead.
    raw = img_path.read_text(encoding="utf-8").splitlines()
    body = [(no, s) for no, s in enumerate(raw, start=1) if not s.strip().startswith("#")]
    image_ids, names, cam_of, X0s, Rs = [], [], [], [], []
    oi, op, uv = [], [], []
    k = 0
    while k < len(body):
        no, s = body[k]
        if not s.strip():
            k += 1
            continue
        f = s.split()
        iid, qw, qx, qy, qz, tx, ty, tz, cid = _numbers(img_path, no, f, "ifffffffi", "an image")
        name = f[9] if len(f) > 9 else str(iid)
        if iid in image_ids:
            raise InputError(f"duplicate IMAGE_ID {iid}", source=str(img_path), where=f"line {no}")
        if cid not in cams:
            raise InputError(f"unknown camera id {cid}", source=str(img_path), where=f"line {no}")
        q = np.array([qw, qx, qy, qz])
        if not 0.5 < np.linalg.norm(q) < 2.0:
            raise InputError(
                "quaternion is not normalised", source=str(img_path), where=f"line {no}"
            )
        q = q / np.linalg.norm(q)
        w, x, y, z = q
        Rcw = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
            ]
        )
        t = np.array([tx, ty, tz])
        image_ids.append(iid)
        names.append(name)
        cam_of.append(cam_index[cid])
        X0s.append(-Rcw.T @ t)
        Rs.append(Rcw.T @ FLIP)
        pts_line = body[k + 1] if k + 1 < len(body) else (no + 1, "")
        f2 = pts_line[1].split()
        if len(f2) % 3:
            raise InputError(
                "expected triplets X Y POINT3D_ID",
                source=str(img_path),
                where=f"line {pts_line[0]}",
            )
        img_idx = len(image_ids) - 1
        for j in range(0, len(f2), 3):
            u, v, p3 = _numbers(img_path, pts_line[0], f2[j : j + 3], "ffi", "a 2D point")
            if p3 == -1:
                continue
            if p3 not in p_index:
                raise InputError(
                    f"unknown POINT3D_ID {p3}", source=str(img_path), where=f"line {pts_line[0]}"
                )
            oi.append(img_idx)
            op.append(p_index[p3])
            uv.append((u, v))
        k += 2
    del lines
    if not image_ids:
        raise InputError("no images in the file", source=str(img_path), where=_end(img_path))
    known = set(image_ids)
    for no, ids in tracks:
        dangling = [i for i in ids if i not in known]
        if dangling:
            raise InputError(
                f"TRACK names IMAGE_ID {dangling[0]}, which is not in images.txt",
                source=str(pts_path),
                where=f"line {no}",
            )
    # readable image ids: COLMAP's image names where they are unique, else its IMAGE_IDs
    ids = names if len(set(names)) == len(names) else [str(i) for i in image_ids]
    uv_arr = np.array(uv, dtype=float).reshape(-1, 2)
    oi_arr = np.array(oi, dtype=np.int64)
    cam_arr = np.array(cam_of, dtype=np.int64)
    xy = np.empty_like(uv_arr)
    for ci, cid in enumerate(cam_ids):
        sel = cam_arr[oi_arr] == ci
        cam = cams[cid]
        und = _undistort(cam, uv_arr[sel])
        cx, cy = cam.principal_point()
        xy[sel, 0] = (und[:, 0] - cx) * pixel_size_mm
        xy[sel, 1] = -(und[:, 1] - cy) * pixel_size_mm
    R = np.array(Rs)
    ang = np.column_stack(opk_from_matrix(R, sequence))
    block = Block.from_arrays(
        camera_c=[cams[c].focal() * pixel_size_mm for c in cam_ids],
        camera_format_mm=[
            (cams[c].width * pixel_size_mm, cams[c].height * pixel_size_mm) for c in cam_ids
        ],
        camera_ids=[str(c) for c in cam_ids],
        image_camera=cam_arr,
        X0=np.array(X0s),
        angles=ang,
        image_ids=ids,
        xyz=np.array(xyz, dtype=float).reshape(-1, 3),
        point_ids=[str(p) for p in pid],
        obs_image=oi_arr,
        obs_point=np.array(op, dtype=np.int64),
        obs_xy=xy,
        obs_sigma=sigma_px * pixel_size_mm,
        sequence=sequence,
        meta={
            "source": str(d),
            "format": "colmap-text",
            "pixel_size_mm": pixel_size_mm,
            "image_names": names,
            "colmap_image_ids": image_ids,
            "colmap_cameras": {
                str(c): {
                    "model": cams[c].model,
                    "width": cams[c].width,
                    "height": cams[c].height,
                    "params": cams[c].params.tolist(),
                }
                for c in cam_ids
            },
        },
    )
    return block


