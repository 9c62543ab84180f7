"""COLMAP import: one streaming pass, only matched keypoints, binary = text, cameras mapped exactly."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import orientviz as ov
from orientviz.camera import project
from orientviz.errors import InputError
from orientviz.io.colmap import FLIP, read_colmap, write_colmap
from orientviz.io.colmap_bin import write_binary_model
from orientviz.io.colmap_scan import parse_numbers, tokenize
from orientviz.io.colmap_text_model import read_text_model

PX = 0.01  # mm, the reader's default pixel size


def _quat(R):
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(R).as_quat()
    return w, x, y, z


def _forward(model: str, p: dict, xn: np.ndarray) -> np.ndarray:
    """COLMAP's projection of normalised coordinates (x right, y down) to pixels."""
    k1 = p.get("k", p.get("k1", 0.0))
    k2, p1, p2 = p.get("k2", 0.0), p.get("p1", 0.0), p.get("p2", 0.0)
    x, y = xn[:, 0], xn[:, 1]
    r2 = x * x + y * y
    rad = k1 * r2 + k2 * r2 * r2
    xd = x + x * rad + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y + y * rad + 2 * p2 * x * y + p1 * (r2 + 2 * y * y)
    fx, fy = p.get("fx", p.get("f")), p.get("fy", p.get("f"))
    return np.column_stack([fx * xd + p["cx"], fy * yd + p["cy"]])


def _scene(tmp_path: Path, model: str, params: dict, *, unmatched: int = 50, rng=None):
    """A COLMAP text model of known truth: 3 cameras around a point cloud."""
    rng = np.random.default_rng(rng)
    X = rng.uniform(-1, 1, (40, 3)) + [0, 0, 10]
    names = ["a.jpg", "b.jpg", "c.jpg"]
    cam_line = f"1 {model} 4000 3000 " + " ".join(repr(float(v)) for v in params.values())
    img_lines, truth = [], []
    for i, name in enumerate(names):
        ang = rng.normal(0, 0.05, 3)
        from orientviz.rotation import matrix_from_opk

        R_ov = matrix_from_opk(*(ang + [np.pi, 0, 0]))  # looking down −z of orientviz
        X0 = np.array([i - 1.0, 0.2 * i, 0.0])
        Rcw = FLIP @ R_ov.T
        t = -Rcw @ X0
        Xc = (Rcw @ (X - X0).T).T
        xn = Xc[:, :2] / Xc[:, 2:3]
        uv = _forward(model, params, xn)
        trip = [f"{u!r} {v!r} {k + 1}" for k, (u, v) in enumerate(uv.tolist())]
        trip += [f"{a:.3f} {b:.3f} -1" for a, b in rng.uniform(0, 3000, (unmatched, 2))]
        order = rng.permutation(len(trip))
        qw, qx, qy, qz = map(float, _quat(Rcw))
        tx, ty, tz = t.tolist()
        img_lines += [f"{i + 1} {qw!r} {qx!r} {qy!r} {qz!r} {tx!r} {ty!r} {tz!r} 1 {name}",
                      " ".join(trip[k] for k in order)]  # fmt: skip
        truth.append((X0, R_ov))
    tracks = [" ".join(f"{i + 1} {k}" for i in range(3)) for k in range(len(X))]
    pts = [
        f"{k + 1} {x!r} {y!r} {z!r} 1 2 3 0.1 {tr}"
        for k, ((x, y, z), tr) in enumerate(zip(X.tolist(), tracks))
    ]
    d = tmp_path / "model"
    d.mkdir()
    (d / "cameras.txt").write_text("# cameras\n" + cam_line + "\n")
    (d / "images.txt").write_text("# images\n" + "\n".join(img_lines) + "\n")
    (d / "points3D.txt").write_text("# points\n" + "\n".join(pts) + "\n")
    return d, X, truth


CAMERAS = {
    "SIMPLE_PINHOLE": {"f": 3200.0, "cx": 2001.5, "cy": 1498.25},
    "PINHOLE": {"fx": 3200.0, "fy": 3150.0, "cx": 2001.5, "cy": 1498.25},
    "SIMPLE_RADIAL": {"f": 3200.0, "cx": 2001.5, "cy": 1498.25, "k": -0.08},
    "OPENCV": {"fx": 3200.0, "fy": 3230.0, "cx": 2001.5, "cy": 1498.25,
               "k1": -0.08, "k2": 0.01, "p1": 3e-4, "p2": -2e-4},
}  # fmt: skip


@pytest.mark.parametrize("model", list(CAMERAS))
def test_cameras_map_exactly_onto_orientvizs_projection(tmp_path, model):
    params = CAMERAS[model]
    d, X, truth = _scene(tmp_path, model, params, rng=3)
    block = read_colmap(d, lens="undistort")
    fx = params.get("fx", params.get("f"))
    assert block.cameras.c[0] == pytest.approx(fx * PX)  # never an average of fx and fy
    assert len(block.observations) == 3 * len(X)  # the unmatched keypoints are gone
    obs = block.observations
    for i, (X0, R) in enumerate(truth):
        sel = obs.image == i
        xy = project(X[obs.point[sel]], X0, R, block.cameras.c[0], 0.0, 0.0)
        assert np.abs(obs.xy[sel] - xy).max() < 1e-9  # mm: exact up to rounding
        assert np.allclose(block.images.X0[i], X0, atol=1e-9)
    fy = params.get("fy", fx)
    assert np.allclose(obs.sigma, [PX, PX * fx / fy])  # σ_y in units of fx


def test_binary_and_text_give_the_same_block(tmp_path):
    d, _, _ = _scene(tmp_path, "OPENCV", CAMERAS["OPENCV"], rng=4)
    b = tmp_path / "bin"
    write_binary_model(read_text_model(d), b)
    t, s = read_colmap(d), read_colmap(b)
    assert t.meta["format"] == "colmap-text" and s.meta["format"] == "colmap-binary"
    assert np.array_equal(t.observations.xy, s.observations.xy)
    assert np.array_equal(t.images.angles, s.images.angles) and t.images.ids == s.images.ids
    assert np.array_equal(t.points.xyz, s.points.xyz)


def test_write_then_read_round_trips_a_simulated_block(tmp_path):
    sim = ov.simulate_block(2, 4, rng=2).block
    write_colmap(sim, tmp_path)
    back = read_colmap(tmp_path, lens="undistort")
    assert np.allclose(back.observations.xy, sim.observations.xy, atol=1e-6)
    b = tmp_path / "bin"
    write_binary_model(read_text_model(tmp_path), b)
    assert np.array_equal(read_colmap(b, lens="undistort").observations.xy, back.observations.xy)


def test_a_truncated_binary_file_names_the_byte(tmp_path):
    d, _, _ = _scene(tmp_path, "PINHOLE", CAMERAS["PINHOLE"], rng=5)
    b = tmp_path / "bin"
    write_binary_model(read_text_model(d), b)
    data = (b / "images.bin").read_bytes()
    (b / "images.bin").write_bytes(data[: len(data) - 10])
    with pytest.raises(InputError, match=r"images\.bin: byte \d+: .*truncated"):
        read_colmap(b)


def test_a_binary_camera_model_outside_the_mapping_is_refused_by_name(tmp_path):
    import struct

    d = tmp_path / "bin"
    d.mkdir()
    (d / "cameras.bin").write_bytes(struct.pack("<QiiQQ", 1, 1, 5, 640, 480) + bytes(64))
    for name in ("images.bin", "points3D.bin"):
        (d / name).write_bytes(struct.pack("<Q", 0))
    with pytest.raises(InputError, match="OPENCV_FISHEYE is not supported"):
        read_colmap(d)


def test_numbers_are_parsed_like_python():
    rng = np.random.default_rng(7)
    vals = rng.uniform(-5000, 5000, 2000)
    words = [f"{v:.6f}" for v in vals] + ["1e-05", "-0.5", "+3", "7", "2.", ".25"]
    text = (" ".join(words) + "\n").encode()
    buf = np.frombuffer(text, np.uint8)
    t = tokenize(buf)
    got, bad = parse_numbers(buf, t.start, t.end)
    assert bad.size == 0
    assert np.array_equal(got, [float(w) for w in words])
    ints, bad = parse_numbers(buf, t.start, t.end, integer=True)
    assert set(bad.tolist()) == {k for k, w in enumerate(words) if not w.lstrip("+-").isdigit()}
    assert ints[-3] == 7 and ints[-4] == 3


def test_long_decimals_are_read_as_float_reads_them():
    # COLMAP writes doubles with 17 significant digits: a token of up to 19 bytes has a
    # mantissa beyond 2**53, where one division of the mantissa is no longer exact
    rng = np.random.default_rng(11)
    vals = np.concatenate([rng.uniform(0, 1, 3000), rng.uniform(-4000, 4000, 3000)])
    words = [f"{v:.17g}" for v in vals] + [repr(float(v)) for v in vals]
    words = [w for w in words if len(w) <= 19 and "e" not in w]
    assert len(words) > 5000
    text = (" ".join(words) + "\n").encode()
    buf = np.frombuffer(text, np.uint8)
    t = tokenize(buf)
    got, bad = parse_numbers(buf, t.start, t.end)
    assert bad.size == 0
    want = np.array([float(w) for w in words])
    assert np.array_equal(got.view(np.int64), want.view(np.int64))


def test_the_shipped_model_is_read_bit_for_bit_as_colmap_wrote_it():
    # every keypoint and point coordinate of axe's text files equals float() of its token
    from orientviz.datasets.sfm import axe_model

    d = axe_model()
    model = read_text_model(d)
    pts = {}
    for line in (d / "points3D.txt").read_text().splitlines():
        if line and not line.startswith("#"):
            f = line.split()
            pts[int(f[0])] = [float(v) for v in f[1:4]]
    xyz = np.array([pts[int(i)] for i in model.point_ids])
    assert np.array_equal(model.xyz.view(np.int64), xyz.view(np.int64))
    lines = [ln for ln in (d / "images.txt").read_text().splitlines() if not ln.startswith("#")]
    rows = []  # image id, point id, x, y of every matched keypoint, as the file has them
    for head, keys in zip(lines[0::2], lines[1::2]):
        f = keys.split()
        for x, y, p in zip(f[0::3], f[1::3], f[2::3]):
            if p != "-1":
                rows.append((int(head.split()[0]), int(p), float(x), float(y)))
    want = np.array(rows)
    got = np.column_stack(
        [model.image_ids[model.obs_image], model.point_ids[model.obs_point], model.obs_uv]
    )
    assert got.shape == want.shape
    got, want = (a[np.lexsort(a.T[::-1])] for a in (got, want))
    assert np.array_equal(got.view(np.int64), want.view(np.int64))
