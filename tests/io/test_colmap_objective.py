"""COLMAP models as they come: COLMAP's objective (distorted pixels) and repeated tracks."""

from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest
from test_colmap_exact import CAMERAS, _scene

from orientviz.cli import main
from orientviz.io.colmap import read_colmap, write_colmap
from orientviz.io.colmap_lens import FREE_TERMS, repeated_observations
from orientviz.io.problem import load_problem

PX = 0.01


def _solve(path, *flags):
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(["solve", str(path), "--free", "--json", *flags])
    return code, json.loads(out.getvalue())


@pytest.mark.parametrize("model", list(CAMERAS))
def test_the_forward_model_reproduces_colmaps_pixels(tmp_path, model):
    """Default import: the observations are COLMAP's pixels (x = u·p, y = −v·p), the
    camera the forward model with COLMAP's parameters: exact data solve to σ0 ≈ 0 px."""
    params = CAMERAS[model]
    d, X, truth = _scene(tmp_path, model, params, rng=3)
    block = read_colmap(d, lens="fixed")
    text = (d / "images.txt").read_text().splitlines()[2].split()
    uv = {int(p): (float(u), float(v)) for u, v, p in zip(text[0::3], text[1::3], text[2::3])}
    obs = block.observations
    first = np.flatnonzero(obs.image == 0)
    for k in first[:5]:
        u, v = uv[int(block.points.ids[obs.point[k]])]
        assert obs.xy[k].tolist() == pytest.approx([u * PX, -v * PX], rel=1e-15)
    assert np.allclose(obs.sigma, PX)  # σ in pixels, both coordinates
    spec = block.cameras.model[0]
    fy = params.get("fy", params.get("f"))
    assert block.cameras.c[0] == pytest.approx(fy * PX)
    assert block.cameras.x0[0] == pytest.approx(params["cx"] * PX)
    assert block.cameras.y0[0] == pytest.approx(-params["cy"] * PX)
    assert spec["model"] == "forward" and spec["free"] == []
    out = tmp_path / "p.json"
    assert main(["import-colmap", str(d), "--fix-lens", "-o", str(out)]) == 0
    code, sol = _solve(out)
    assert code == 0
    assert sol["sigma0"] < 1e-6  # px: COLMAP's projection, exactly
    assert load_problem(out).units.image == "px"


def test_refine_frees_what_colmap_refines_and_recovers_the_camera(tmp_path):
    """The default frees focal length and distortion (FREE_TERMS), not the principal
    point; a start 1 % off in f and without k is refined to the true camera."""
    params = dict(CAMERAS["SIMPLE_RADIAL"])
    d, X, truth = _scene(tmp_path, "SIMPLE_RADIAL", params, rng=4)
    assert read_colmap(d).cameras.model[0]["free"] == list(FREE_TERMS["SIMPLE_RADIAL"])
    cams = d / "cameras.txt"
    cams.write_text(cams.read_text().replace("3200.0", "3232.0").replace("-0.08", "0.0"))
    out = tmp_path / "p.json"
    assert main(["import-colmap", str(d), "-o", str(out)]) == 0
    adj = tmp_path / "adj.json"
    code, sol = _solve(out, "-o", str(adj))
    assert code == 0 and sol["sigma0"] < 1e-5
    par = {p["name"]: p["value"] for p in sol["parameters"]}
    assert par["1.c"] == pytest.approx(3200.0, rel=1e-7)
    assert par["1.k1"] == pytest.approx(-0.08, abs=1e-7)
    assert "1.x0" not in par  # the principal point is held
    # solve -o writes the refined camera; write_colmap writes it as COLMAP's camera
    back = tmp_path / "back"
    write_colmap(load_problem(adj).data, back)
    line = (back / "cameras.txt").read_text().splitlines()[-1].split()
    assert line[1] == "SIMPLE_RADIAL"
    f, cx, cy, k = map(float, line[4:8])
    assert f == pytest.approx(3200.0, rel=1e-7) and k == pytest.approx(-0.08, abs=1e-7)
    assert (cx, cy) == (params["cx"], params["cy"])


def test_write_read_round_trip_keeps_colmaps_pixels(tmp_path):
    d, X, truth = _scene(tmp_path, "OPENCV", CAMERAS["OPENCV"], rng=5)
    a = read_colmap(d)
    write_colmap(a, tmp_path / "w")
    b = read_colmap(tmp_path / "w")
    np.testing.assert_allclose(b.observations.xy, a.observations.xy, atol=1e-8)  # 6 decimals px
    assert b.cameras.model[0]["values"] == pytest.approx(a.cameras.model[0]["values"], abs=1e-15)
    np.testing.assert_allclose([b.cameras.c, b.cameras.x0, b.cameras.y0],
                               [a.cameras.c, a.cameras.x0, a.cameras.y0], rtol=1e-15)  # fmt: skip


def test_repeated_observations_keep_the_first():
    img = np.array([0, 0, 1, 0, 1, 2])
    pt = np.array([5, 7, 5, 5, 5, 5])
    uv = np.array([[1.0, 1], [2, 2], [3, 3], [4, 5], [3, 3], [9, 9]])
    keep, far = repeated_observations(img, pt, uv)
    assert keep.tolist() == [0, 1, 2, 5]  # (0, 5) again at 3, (1, 5) again at 4
    assert far == pytest.approx(5.0)  # (4, 5) − (1, 1)
    keep, far = repeated_observations(img[:3], pt[:3], uv[:3])
    assert keep.tolist() == [0, 1, 2] and far == 0.0


def test_a_point_seen_twice_in_one_image_is_imported_and_solves(tmp_path, capsys):
    """A track with two keypoints of one image: the first is kept, the count is printed,
    and the imported file solves (exit 0) instead of being refused."""
    d, X, truth = _scene(tmp_path, "SIMPLE_RADIAL", CAMERAS["SIMPLE_RADIAL"], rng=6)
    lines = (d / "images.txt").read_text().splitlines()
    trip = np.array(lines[2].split()).reshape(-1, 3)
    u, v, pid = next(t for t in trip if t[2] != "-1")  # a matched keypoint of image 1
    lines[2] += f" {float(u) + 0.5!r} {v} {pid}"  # a second keypoint of the same point
    k = len(trip)
    (d / "images.txt").write_text("\n".join(lines) + "\n")
    pts = (d / "points3D.txt").read_text().splitlines()
    at = next(i for i, ln in enumerate(pts) if ln.split()[0] == pid)
    pts[at] += f" 1 {k}"
    (d / "points3D.txt").write_text("\n".join(pts) + "\n")
    block = read_colmap(d)
    assert block.meta["colmap_repeated"] == [1, pytest.approx(0.5)]
    out = tmp_path / "p.json"
    assert main(["import-colmap", str(d), "-o", str(out)]) == 0
    said = capsys.readouterr().out
    assert "1 observation(s) of a point already seen in the same image left out" in said
    code, sol = _solve(out)
    assert code == 0 and sol["sigma0"] < 1e-6  # the kept one is the exact keypoint
