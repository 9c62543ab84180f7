"""BAL import/export (orientviz.io.bal)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import orientviz as ov
from orientviz.io.bal import read_bal, write_bal
from orientviz.rotation import matrix_from_rotvec

MAKE_BLOCK = Path("/work/shared/bench/make_block.py")


def _wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def _bal_text(rotvecs, ts, f, points, obs, k=(0.0, 0.0)):
    """A BAL file written independently from the formula P = R X + t, x = −f P_x / P_z."""
    lines = [f"{len(rotvecs)} {len(points)} {len(obs)}"]
    for c, p in obs:
        P = matrix_from_rotvec(rotvecs[c]) @ points[p] + ts[c]
        q = -P[:2] / P[2]
        d = 1 + k[0] * (q @ q) + k[1] * (q @ q) ** 2
        x, y = f * d * q
        lines.append(f"{c} {p} {x:.9f} {y:.9f}")
    for r, t in zip(rotvecs, ts):
        lines += [repr(float(v)) for v in (*r, *t, f, *k)]
    lines += [repr(float(v)) for v in np.ravel(points)]
    return "\n".join(lines) + "\n"


def _scene():
    rng = np.random.default_rng(2)
    pts = np.column_stack(
        [rng.uniform(-500, 500, 12), rng.uniform(-500, 500, 12), rng.uniform(0, 50, 12)]
    )
    X0 = np.array([[-300.0, 0.0, 1500.0], [300.0, 20.0, 1510.0]])
    rot = np.array([[np.pi, 0.01, 0.02], [np.pi - 0.02, 0.0, 0.1]])  # R_bal: looking down
    ts = np.array([-matrix_from_rotvec(r) @ x for r, x in zip(rot, X0)])
    obs = [(c, p) for c in range(2) for p in range(12)]
    return pts, X0, rot, ts, obs


def test_bal_convention_matches_orientviz_camera(tmp_path):
    pts, X0, rot, ts, obs = _scene()
    path = tmp_path / "scene.bal"
    path.write_text(_bal_text(rot, ts, 15200.0, pts, obs))
    b = read_bal(path, pixel_size_mm=0.01)
    assert b.cameras.c.tolist() == [152.0]
    np.testing.assert_allclose(b.images.X0, X0, atol=1e-9)
    np.testing.assert_allclose(b.points.xyz, pts)
    # orientviz's collinearity reproduces the BAL pixel coordinates (written to 1e-9 px)
    np.testing.assert_allclose(b.project(), b.observations.xy, atol=1e-10)
    # R (image → object) is R_balᵀ
    np.testing.assert_allclose(b.rotations()[0], matrix_from_rotvec(rot[0]).T, atol=1e-12)


def test_radial_distortion_is_removed(tmp_path):
    pts, X0, rot, ts, obs = _scene()
    path = tmp_path / "dist.bal"
    path.write_text(_bal_text(rot, ts, 15200.0, pts, obs, k=(-0.05, 0.01)))
    b = read_bal(path)
    # 20 fixed-point steps converge far below the 1e-9 px written precision for |k r²| ≈ 0.01
    np.testing.assert_allclose(b.project(), b.observations.xy, atol=1e-9)


def test_write_read_round_trip(tmp_path):
    pts, X0, rot, ts, obs = _scene()
    path = tmp_path / "a.bal"
    path.write_text(_bal_text(rot, ts, 15200.0, pts, obs))
    b = read_bal(path, sigma_px=0.5)
    write_bal(b, tmp_path / "b.bal")
    b2 = read_bal(tmp_path / "b.bal", sigma_px=0.5)
    np.testing.assert_allclose(b2.images.X0, b.images.X0, atol=1e-9)
    np.testing.assert_allclose(_wrap(b2.images.angles - b.images.angles), 0, atol=1e-12)
    np.testing.assert_allclose(b2.points.xyz, b.points.xyz)
    np.testing.assert_allclose(b2.observations.xy, b.observations.xy, atol=1e-11)  # 9 decimals px
    np.testing.assert_array_equal(b2.observations.point, b.observations.point)
    assert np.all(b2.observations.sigma == 0.005)


@pytest.mark.parametrize(
    "text, where",
    [
        ("2 3\n", "line 1"),
        ("1 1 2\n0 0 1.0 2.0\n", "line 2"),
        ("1 1 2\n0 0 1.0 2.0\n0 0 1.0\n", "line 3"),
        ("1 1 1\n0 0 1.0 abc\n", "line 2"),
        ("1 1 1\n0 5 1.0 2.0\n", "line 2"),
        ("1 1 1\n0 0 1.0 2.0\n" + "0\n" * 9 + "1\n2\n", "line 13"),
        ("1 1 1\n0 0 1.0 2.0\n" + "0\n" * 4 + "nan\n" + "0\n" * 4 + "1\n2\n3\n", "line 7"),
    ],
)
def test_broken_files_name_file_and_line(tmp_path, text, where):
    path = tmp_path / "broken.bal"
    path.write_text(text)
    with pytest.raises(ov.InputError) as info:
        read_bal(path)
    msg = str(info.value)
    assert "broken.bal" in msg and where in msg


def test_missing_file_is_input_error(tmp_path):
    with pytest.raises(ov.InputError, match="no such file"):
        read_bal(tmp_path / "nope.bal")


@pytest.mark.skipif(not MAKE_BLOCK.exists(), reason="peer bench generator not available")
def test_reads_make_block_files(tmp_path):
    env = dict(os.environ, ORIENTVIZ_BENCH_DATA=str(tmp_path))
    subprocess.run(
        [sys.executable, str(MAKE_BLOCK), "--size", "small", "--out", str(tmp_path)],
        check=True,
        capture_output=True,
        env=env,
    )
    bal = next(tmp_path.glob("*.bal"))
    z = np.load(bal.with_suffix(".npz"))
    b = read_bal(bal, pixel_size_mm=float(z["pixel_size_mm"]))
    np.testing.assert_allclose(b.images.X0, z["cam_init_C"], atol=1e-6)
    ang = np.radians(z["cam_init_opk_gon"] * 0.9)
    np.testing.assert_allclose(_wrap(b.images.angles - ang), 0, atol=1e-12)
    np.testing.assert_allclose(b.points.xyz, z["pt_init"], atol=1e-9)  # 10 decimals in BAL
    np.testing.assert_allclose(b.observations.xy, z["obs_xy_mm"], atol=1e-8)  # 6 decimals px


def test_cli_import_bal_writes_problem_file(tmp_path):
    from orientviz.cli import main
    from orientviz.io.problem import load_problem

    pts, X0, rot, ts, obs = _scene()
    path = tmp_path / "scene.bal"
    path.write_text(_bal_text(rot, ts, 15200.0, pts, obs))
    out = tmp_path / "scene.json"
    assert main(["import-bal", str(path), "-o", str(out)]) == 0
    block = load_problem(out).data
    assert isinstance(block, ov.Block)
    np.testing.assert_allclose(block.images.X0, X0, atol=1e-6)
