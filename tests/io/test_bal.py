"""BAL import/export (orientviz.io.bal)."""

from __future__ import annotations

import os
import re
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
    rot = np.array([[0.0, 0.01, 0.02], [-0.02, 0.0, 0.1]])  # R_bal ≈ I: the camera looks down (−z)
    ts = np.array([-matrix_from_rotvec(r) @ x for r, x in zip(rot, X0)])
    obs = [(c, p) for c in range(2) for p in range(12)]
    return pts, X0, rot, ts, obs


def test_bal_convention_matches_orientviz_camera(tmp_path):
    pts, X0, rot, ts, obs = _scene()
    path = tmp_path / "scene.bal"
    path.write_text(_bal_text(rot, ts, 15200.0, pts, obs))
    b = read_bal(path, pixel_size_mm=0.01)
    assert b.cameras.c.tolist() == [152.0, 152.0]  # one camera per BAL camera
    np.testing.assert_allclose(b.images.X0, X0, atol=1e-9)
    np.testing.assert_allclose(b.points.xyz, pts)
    # orientviz's collinearity reproduces the BAL pixel coordinates (written to 1e-9 px)
    np.testing.assert_allclose(b.project(), b.observations.xy, atol=1e-10)
    # R (image → object) is R_balᵀ
    np.testing.assert_allclose(b.rotations()[0], matrix_from_rotvec(rot[0]).T, atol=1e-12)


def _solve(tmp_path, bal, *flags):
    """import-bal + solve --free --json of a BAL file: (exit code, solution dict)."""
    import contextlib
    import io
    import json

    from orientviz.cli import main

    out = tmp_path / "p.json"
    assert main(["import-bal", str(bal), "-o", str(out), *flags]) == 0
    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        code = main(["solve", str(out), "--free", "--json"])
    return code, json.loads(text.getvalue())


def test_distorted_observations_are_kept_and_the_forward_model_fits_them(tmp_path):
    """The observations stay the file's distorted pixels; the bundle's forward lens model
    with the file's f, k1, k2 reproduces them (exact data: zero residuals)."""
    pts, X0, rot, ts, obs = _scene()
    path = tmp_path / "dist.bal"
    path.write_text(_bal_text(rot, ts, 15200.0, pts, obs, k=(-0.05, 0.01)))
    b = read_bal(path, lens="fixed")
    raw = np.array([ln.split()[2:4] for ln in path.read_text().splitlines()[1:25]], float)
    np.testing.assert_allclose(b.observations.xy, raw * 0.01, atol=0, rtol=0)
    # the pinhole projection misses them by the distortion (≈ k1 r² of 0.1–1 px) …
    assert np.abs(b.project() - b.observations.xy).max() > 1e-3
    spec = b.cameras.model[0]
    assert spec["model"] == "forward" and spec["free"] == []
    assert spec["values"] == {"k1": -0.05, "k2": 0.01}
    # … the forward model of orientviz solve fits them exactly
    code, sol = _solve(tmp_path, path, "--fix-lens")
    assert code == 0
    assert sol["sigma0"] < 1e-6  # σ = 1 px: residuals below 1e-6 px


def _four_cameras(tmp_path):
    """A BAL file of 4 cameras and 80 points whose exact observations have f = 15200 px,
    k1 = −0.05, k2 = 0.01, and whose start values say f 1 % long and k1 = k2 = 0."""
    rng = np.random.default_rng(5)
    pts = rng.uniform([-400, -400, 0], [400, 400, 300], (80, 3))
    X0 = np.array([[-300, -50, 1500], [300, 0, 1450], [0, 300, 1550], [0, -300, 1500.0]])
    rot = rng.normal(0, 0.05, (4, 3))
    ts = np.array([-matrix_from_rotvec(r) @ x for r, x in zip(rot, X0)])
    obs = [(c, p) for c in range(4) for p in range(80)]
    text = _bal_text(rot, ts, 15200.0, pts, obs, k=(-0.05, 0.01)).splitlines()
    for c in range(4):
        at = 1 + len(obs) + 9 * c
        text[at + 6 : at + 9] = [repr(15200.0 * 1.01), "0.0", "0.0"]
    path = tmp_path / "d.bal"
    path.write_text("\n".join(text) + "\n")
    return path


def test_lens_is_refined_per_camera_by_default(tmp_path):
    """Default import: f, k1, k2 of every camera free; start values 1 % off in f and
    without distortion are refined to the true ones (exact observations)."""
    path = _four_cameras(tmp_path)
    b = read_bal(path)
    assert [m["free"] for m in b.cameras.model] == [["c", "k1", "k2"]] * 4
    assert b.meta["lens"] == "refine"
    code, sol = _solve(tmp_path, path)
    assert code == 0 and sol["sigma0"] < 1e-5
    par = {p["name"]: p["value"] for p in sol["parameters"]}
    for c in range(4):
        assert par[f"cam{c}.c"] == pytest.approx(15200.0, rel=1e-7)  # px
        assert par[f"cam{c}.k1"] == pytest.approx(-0.05, abs=1e-6)
        assert par[f"cam{c}.k2"] == pytest.approx(0.01, abs=1e-5)
    with pytest.raises(ov.InputError, match="lens"):
        read_bal(path, lens="undistort")


def test_the_report_prints_the_lens_terms_as_pure_numbers(tmp_path, capsys):
    """The text report's camera line gives c in the file's pixels and k1, k2 bare (no unit "1")."""
    from orientviz.cli import main

    prob = tmp_path / "four.json"
    assert main(["import-bal", str(_four_cameras(tmp_path)), "-o", str(prob)]) == 0
    capsys.readouterr()
    assert main(["solve", str(prob), "--free"]) == 0
    line = next(s for s in capsys.readouterr().out.splitlines() if s.startswith("camera cam0 "))
    assert re.search(r"\bc [0-9.]+ ± \S+ px,", line), line
    for term in ("k1", "k2"):
        assert re.search(rf"\b{term} -?[0-9.e+-]+ ± [0-9.e+-]+(,|$)", line), line
    assert "y0 0 (fixed)" in line, line  # the y flip of a zero principal point is no "-0"


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


def test_a_principal_point_is_written_into_the_observations(tmp_path):
    """BAL has no principal point: a camera with one (a COLMAP import) is written with its
    observations measured from it, so the BAL file projects exactly as the block does."""
    pts, X0, rot, ts, obs = _scene()
    path = tmp_path / "a.bal"
    path.write_text(_bal_text(rot, ts, 15200.0, pts, obs, k=(-0.12, 0.03)))
    b = read_bal(path)  # cameras with x0 = y0 = 0 and the forward lens model
    shifted = b.copy()
    pp = np.array([[1.3, -0.7], [-0.4, 2.1]])  # mm, one principal point per camera
    shifted.cameras.x0, shifted.cameras.y0 = pp[:, 0], pp[:, 1]
    shifted.observations.xy = b.observations.xy + pp[b.images.camera[b.observations.image]]
    write_bal(shifted, tmp_path / "s.bal")
    back = read_bal(tmp_path / "s.bal")
    np.testing.assert_allclose(back.observations.xy, b.observations.xy, atol=1e-11)
    assert back.cameras.model == b.cameras.model  # f, k1, k2 as they were


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


def test_cli_import_bal_writes_problem_file(tmp_path, capsys):
    from orientviz.cli import main
    from orientviz.io.problem import load_problem

    pts, X0, rot, ts, obs = _scene()
    path = tmp_path / "scene.bal"
    path.write_text(_bal_text(rot, ts, 15200.0, pts, obs))
    out = tmp_path / "scene.json"
    assert main(["import-bal", str(path), "-o", str(out)]) == 0
    said = capsys.readouterr().out
    problem = load_problem(out)
    block = problem.data
    assert isinstance(block, ov.Block)
    np.testing.assert_allclose(block.images.X0, X0, atol=1e-6)
    # written in pixels: c is BAL's f; the datum hint names --free and --fix
    assert problem.units.image == "px" and problem.units.pixel_size == 0.01
    assert problem.units.angle == "deg"
    np.testing.assert_allclose(block.cameras.c, 152.0)
    assert "--free" in said and "--fix img0 --fix img1:X0" in said
    assert "f, k1, k2 of each camera free" in said


def test_the_datum_hint_solves(tmp_path, capsys):
    """Both ways the hint names solve an imported BAL block (exit 0)."""
    from orientviz.cli import main

    path = _four_cameras(tmp_path)
    out = tmp_path / "p.json"
    assert main(["import-bal", str(path), "-o", str(out)]) == 0
    assert main(["solve", str(out)]) == 3  # no datum: refused
    assert main(["solve", str(out), "--free"]) == 0
    assert main(["solve", str(out), "--fix", "img0", "--fix", "img1:X0"]) == 0


def test_solve_output_and_export_bal_carry_the_refined_cameras(tmp_path):
    """solve -o writes the refined f, k1, k2 into the problem file; export-bal writes them
    back into a BAL file whose cameras read back the same."""
    from orientviz.cli import main
    from orientviz.io.bal import bal_cameras
    from orientviz.io.problem import load_problem

    path = _four_cameras(tmp_path)
    prob = tmp_path / "s.json"
    assert main(["import-bal", str(path), "-o", str(prob)]) == 0
    adj = tmp_path / "adj.json"
    assert main(["solve", str(prob), "--free", "--json", "-o", str(adj)]) == 0
    cams = bal_cameras(load_problem(adj).data, 0.01)
    np.testing.assert_allclose(cams[:, 6], 15200.0, rtol=1e-7)  # the refined f, not 15352
    np.testing.assert_allclose(cams[:, 7], -0.05, atol=1e-6)
    np.testing.assert_allclose(cams[:, 8], 0.01, atol=1e-5)
    out = tmp_path / "adj.bal"
    assert main(["export-bal", str(adj), "-o", str(out)]) == 0
    back = bal_cameras(read_bal(out), 0.01)
    np.testing.assert_allclose(back, cams, rtol=1e-12, atol=1e-12)
    assert main(["export-bal", str(prob), "-o", str(tmp_path / "start.bal")]) == 0
    start = bal_cameras(read_bal(tmp_path / "start.bal"), 0.01)
    np.testing.assert_allclose(start[:, 6], 15352.0, rtol=1e-12)  # the file's own values


def test_a_solve_stopped_by_the_iteration_limit_writes_its_last_iterate(tmp_path, capsys):
    """-o at the iteration limit: the last iterate, marked in the description; the message
    names the options that would help (--max-iter, and --ftol where it is off)."""
    from orientviz.cli import main
    from orientviz.io.problem import load_problem
    from orientviz.io.solve import LAST_ITERATE_MARK

    path = _four_cameras(tmp_path)
    prob = tmp_path / "s.json"
    assert main(["import-bal", str(path), "-o", str(prob)]) == 0
    start = load_problem(prob)
    assert start.options["damping"] == "trust" and start.options["ftol"] == 1e-6
    out = tmp_path / "last.json"
    capsys.readouterr()
    code = main(["solve", str(prob), "--free", "--max-iter", "2", "--ftol", "0", "-o", str(out)])
    assert code == 3
    err = capsys.readouterr().err
    assert "reached the maximum of 2 iterations" in err
    assert "--max-iter 8" in err and "--ftol 1e-6" in err and "last iterate" in err
    last = load_problem(out)
    assert LAST_ITERATE_MARK in last.description
    moved = np.abs(last.data.cameras.c - start.data.cameras.c).max()
    assert moved > 0  # the steps were taken and written (the first holds the lens)
    # without -o nothing is written, and the hint leaves out the file
    code = main(["solve", str(prob), "--free", "--max-iter", "2"])
    err = capsys.readouterr().err
    assert code == 3 and "last iterate" not in err and "--ftol" not in err  # ftol is on
