"""COLMAP text models: conventions checked against COLMAP's documented projection."""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.io.colmap import write_colmap


def _block(rng):
    X0 = np.array([[0.0, 0.0, 1500.0], [900.0, 20.0, 1510.0], [1800.0, -10.0, 1490.0]])
    ang = np.array([[0.01, -0.02, 0.03], [-0.015, 0.01, 3.13], [0.02, 0.005, -0.02]])
    xyz = np.column_stack(
        [rng.uniform(300, 1500, 40), rng.uniform(-600, 600, 40), rng.uniform(0, 100, 40)]
    )
    R = ov.matrix_from_opk(ang[:, 0], ang[:, 1], ang[:, 2])
    from orientviz.camera import project

    oi, op, xy = [], [], []
    for i in range(3):
        p = project(xyz, X0[i], R[i], 152.0)
        ok = np.all(np.abs(p) < 110, axis=1)
        oi += [i] * int(ok.sum())
        op += list(np.flatnonzero(ok))
        xy.append(p[ok])
    return ov.Block.from_arrays(
        camera_c=[152.0],
        image_camera=[0, 0, 0],
        X0=X0,
        angles=ang,
        xyz=xyz,
        obs_image=oi,
        obs_point=op,
        obs_xy=np.vstack(xy),
    )


def test_round_trip_and_colmap_projection(tmp_path):
    b = _block(np.random.default_rng(1))
    write_colmap(b, tmp_path, pixel_size_mm=0.01)
    # COLMAP's own convention, written out independently: X_cam = R(q) X + t, u = f X/Z + cx
    cams = [
        l.split()
        for l in (tmp_path / "cameras.txt").read_text().splitlines()
        if not l.startswith("#")
    ]
    f, cx, cy = map(float, cams[0][4:7])
    raw = [l for l in (tmp_path / "images.txt").read_text().splitlines() if not l.startswith("#")]
    pts = {
        int(l.split()[0]): np.array(l.split()[1:4], float)
        for l in (tmp_path / "points3D.txt").read_text().splitlines()
        if not l.startswith("#")
    }
    for k in range(0, len(raw), 2):
        h = raw[k].split()
        qw, qx, qy, qz, tx, ty, tz = map(float, h[1:8])
        from scipy.spatial.transform import Rotation

        Rcw = Rotation.from_quat([qx, qy, qz, qw]).as_matrix()
        obs = np.array(raw[k + 1].split(), float).reshape(-1, 3)
        for u, v, pid in obs:
            Xc = Rcw @ pts[int(pid)] + [tx, ty, tz]
            assert Xc[2] > 0  # in front of the camera, COLMAP looks along +z
            assert u == pytest.approx(f * Xc[0] / Xc[2] + cx, abs=1e-5)
            assert v == pytest.approx(f * Xc[1] / Xc[2] + cy, abs=1e-5)
    back = ov.read_colmap(tmp_path, pixel_size_mm=0.01)
    np.testing.assert_allclose(back.images.X0, b.images.X0, atol=1e-6)
    np.testing.assert_allclose(back.rotations(), b.rotations(), atol=1e-9)
    np.testing.assert_allclose(back.points.xyz, b.points.xyz, atol=1e-6)
    np.testing.assert_allclose(back.cameras.c, [152.0])
    # noise-free observations reproject exactly after the round trip
    np.testing.assert_allclose(back.residuals(), 0.0, atol=1e-6)


def test_distortion_is_removed_at_import(tmp_path):
    b = _block(np.random.default_rng(2))
    write_colmap(b, tmp_path, pixel_size_mm=0.01)
    # distort the written pixel coordinates with an OPENCV model and declare it
    cam = (tmp_path / "cameras.txt").read_text().splitlines()[-1].split()
    w, h, f, cx, cy = int(cam[2]), int(cam[3]), float(cam[4]), float(cam[5]), float(cam[6])
    k1, k2, p1, p2 = -0.05, 0.01, 1e-4, -2e-4
    (tmp_path / "cameras.txt").write_text(
        f"1 OPENCV {w} {h} {f} {f} {cx} {cy} {k1} {k2} {p1} {p2}\n"
    )
    lines = (tmp_path / "images.txt").read_text().splitlines()
    out = []
    for l in lines:
        if l.startswith("#") or len(l.split()) % 3 or len(l.split()) == 10:
            out.append(l)
            continue
        a = np.array(l.split(), float).reshape(-1, 3)
        x, y = (a[:, 0] - cx) / f, (a[:, 1] - cy) / f
        r2 = x * x + y * y
        rad = 1 + k1 * r2 + k2 * r2 * r2
        xd = x * rad + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        yd = y * rad + 2 * p2 * x * y + p1 * (r2 + 2 * y * y)
        a[:, 0], a[:, 1] = xd * f + cx, yd * f + cy
        out.append(" ".join(f"{u:.8f} {v:.8f} {int(p)}" for u, v, p in a))
    (tmp_path / "images.txt").write_text("\n".join(out) + "\n")
    back = ov.read_colmap(tmp_path, pixel_size_mm=0.01, lens="undistort")
    # undistortion recovers the pinhole observations to well below a micrometre
    np.testing.assert_allclose(back.residuals(), 0.0, atol=1e-4)


@pytest.mark.parametrize(
    "name,content,where",
    [
        ("cameras.txt", "1 FISHEYE 10 10 1 2 3\n", "line 1"),
        ("cameras.txt", "1 PINHOLE 10 10 1 2 3\n", "line 1"),
        ("cameras.txt", "1 SIMPLE_PINHOLE 10 ten 1 2 3\n", "line 1"),
        ("points3D.txt", "# c\n1 0 0 nan 1 1 1 0\n", "line 2"),
    ],
)
def test_broken_files_name_file_and_line(tmp_path, name, content, where):
    write_colmap(_block(np.random.default_rng(3)), tmp_path)
    (tmp_path / name).write_text(content)
    with pytest.raises(ov.InputError) as info:
        ov.read_colmap(tmp_path)
    assert name in str(info.value) and where in str(info.value)


def test_missing_directory(tmp_path):
    with pytest.raises(ov.InputError, match="expected a directory"):
        ov.read_colmap(tmp_path / "nope")
