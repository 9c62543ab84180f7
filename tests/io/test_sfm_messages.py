"""Messages that fit the data: no aerial words for a hand-held (non-aerial) block."""

from __future__ import annotations

import numpy as np

import orientviz as ov
from orientviz.plausibility import check_block

PIXEL_MM = 0.01  # the importers' nominal pixel size


def _behind_message(block):
    found = [f for f in check_block(block) if f.check == "behind"]
    assert found, "expected the points-behind finding"
    return found[0].message


def test_points_behind_an_aerial_camera_speak_of_heights():
    block = ov.simulate_block(1, 4, rng=3).block
    j = block.observations.point[block.points.role[block.observations.point] == 0][0]  # a tie
    block.points.xyz[j, 2] = block.images.X0[:, 2].max() + 100.0  # above the cameras
    assert "flying height" in _behind_message(block)


def test_points_behind_a_hand_held_camera_do_not():
    block = ov.simulate_block(1, 4, rng=3).block
    block.images.angles[:, 0] += np.pi / 2  # every camera looks horizontally
    k = np.flatnonzero(block.points.role[block.observations.point] == 0)[0]  # a tie point's ray
    i, j = block.observations.image[k], block.observations.point[k]
    block.points.xyz[j] = block.images.X0[i] + [0.0, -50.0, 0.0]  # behind image i
    msg = _behind_message(block)
    assert "flying height" not in msg and "heights" not in msg
    assert "check the angles of those images" in msg


def test_a_far_point_of_a_reconstruction_is_named_in_model_units():
    """A file in model units (an SfM model's arbitrary scale) never hears of metres."""
    block = ov.simulate_block(1, 4, rng=3).block
    j = int(np.flatnonzero(block.points.role == 0)[0])  # a tie point
    block.points.xyz[j] = block.points.xyz[j] + [0.0, 0.0, 1e6]  # far above the block
    msgs = {
        unit: next(f.message for f in check_block(block, length=unit) if f.check == "far-away")
        for unit in ("m", "model")
    }
    assert " m from the block's centre" in msgs["m"]
    assert " model units from the block's centre" in msgs["model"]
    assert " m " not in msgs["model"] and not msgs["model"].endswith(" m")


def test_a_pixel_file_hears_of_its_image_coordinates_in_pixels():
    block = ov.simulate_block(1, 4, rng=3).block
    block.observations.xy[0] = [0.0, -5000.0]  # mm, y up: far outside the format
    mm = next(f.message for f in check_block(block) if f.check == "image-outside")
    px = next(f.message for f in check_block(block, pixel_mm=0.01) if f.check == "image-outside")
    assert mm.startswith("y = -5000 mm") and "(half format 152 mm)" in mm  # c = 152 mm
    # the pixel file's own number: y down, 0.01 mm per pixel
    assert px.startswith("y = 500000 px") and "(half format 15200 px)" in px


def test_only_a_real_frame_looking_down_is_aerial():
    from orientviz.plausibility import is_aerial

    block = ov.simulate_block(1, 4, rng=3).block
    assert is_aerial(block) and is_aerial(block, "ft")
    assert not is_aerial(block, "model")  # a reconstruction's Z points anywhere
    block.images.angles[:, 0] += np.pi / 2  # every camera looks horizontally
    assert not is_aerial(block)


def _bal(path, X0, points, f=1000.0, rotvec=(0.0, 0.0, 0.0)):
    """A BAL file of cameras at ``X0``, all turned by ``rotvec`` (default R = I: looking
    along −z), with exact observations (P = R (X − X0), x = −f P_x / P_z)."""
    from orientviz.rotation import matrix_from_rotvec

    R = matrix_from_rotvec(np.asarray(rotvec, dtype=float))
    obs = [(c, p) for c in range(len(X0)) for p in range(len(points))]
    lines = [f"{len(X0)} {len(points)} {len(obs)}"]
    for c, p in obs:
        P = R @ (points[p] - X0[c])  # P = R X + t with t = −R X0
        lines.append(f"{c} {p} {-f * P[0] / P[2]:.9f} {-f * P[1] / P[2]:.9f}")
    for x in X0:
        t = -R @ x
        lines += [repr(float(v)) for v in rotvec] + [repr(float(v)) for v in t]
        lines += [repr(f), "0.0", "0.0"]
    lines += [repr(float(v)) for v in np.ravel(points)]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_an_imported_reconstruction_is_reported_in_model_units(tmp_path, capsys):
    """import-bal writes model units (no control: arbitrary scale); ``solve`` reports
    lengths in them, and its small intersection angles in the file's degrees as a weak
    depth along the rays (not "height", not gon). (With control the unit is m:
    tests/io/test_import_export.py.)"""
    from orientviz.cli import main
    from orientviz.io.problem import load_problem

    rng = np.random.default_rng(4)
    pts = rng.uniform([-3, -3, -2], [3, 3, 2], (40, 3))
    X0 = np.array([[-0.2, 0.0, 30.0], [0.2, 0.1, 30.0], [0.0, -0.2, 31.0], [0.1, 0.2, 29.0]])
    out = tmp_path / "m.json"
    bal = _bal(tmp_path / "m.bal", X0, pts)
    assert main(["import-bal", str(bal), "--fix-lens", "-o", str(out)]) == 0
    assert load_problem(out).units.length == "model"
    capsys.readouterr()
    assert main(["solve", str(out), "--free"]) == 0
    text = capsys.readouterr().out
    assert "length model units" in text and "X0 Y0 Z0 ± σ [model units]" in text
    assert "[m]" not in text
    assert "intersection angle below 9 deg: weak depth along the rays (" in text
    assert "weak height" not in text and " gon" not in text
    # the HTML report: residuals and σ0 in the file's pixels, a plan view, no terrain
    import html
    import re

    page = tmp_path / "r.html"
    assert main(["solve", str(out), "--free", "--report", str(page)]) == 0
    words = html.unescape(re.sub(r"<[^>]+>", " ", re.sub(r"<img[^>]*>", "", page.read_text())))
    assert "v [px]" in words and "σ0 a posteriori in the image" in words
    assert "Plan view on the X-Y plane" in words and "model units" in words
    for foreign in ("µm", "[m]", " gon", "terrain height", "weak height"):
        assert foreign not in words, foreign
    # export: adjusted.json keeps the file's units, the CSV tables label them
    from orientviz.report import image_table

    assert main(["export", str(out), "-d", str(tmp_path / "x"), "--no-adjust"]) == 0
    again = load_problem(tmp_path / "x" / "adjusted.json")
    assert (again.units.length, again.units.image, again.units.angle) == ("model", "px", "deg")
    head = (tmp_path / "x" / "images.csv").read_text().splitlines()[0]
    assert "X0[model]" in head and "rms_vx[px]" in head and "[m]" not in head
    block = load_problem(out).data
    px = image_table(block, length="model", pixel_mm=PIXEL_MM).columns["rms_vx"]
    um = image_table(block).columns["rms_vx"]  # the same residuals in µm of 0.01 mm pixels
    np.testing.assert_allclose(px, um / 10.0, rtol=1e-12)


def test_control_in_a_file_of_model_units_is_a_warning():
    """Metric control in a model-unit file is a contradiction: said, not silently read."""
    block = ov.simulate_block(1, 4, rng=3).block  # has control points
    n = int(np.sum(block.points.role == ov.CONTROL))
    assert n > 0
    said = [f for f in check_block(block, length="model") if f.check == "model-control"]
    assert len(said) == 1 and said[0].level == "warning" and said[0].count == n
    assert f"{n} control point(s)" in said[0].message and '"length": "m"' in said[0].message
    assert not [f for f in check_block(block) if f.check == "model-control"]  # metres: fine


def test_an_imported_model_that_does_not_fit_says_so(tmp_path, capsys):
    """A reconstruction whose lens is held without the distortion its pixels carry
    (``import-bal --fix-lens``, k1 left out of the file): σ0 ≫ 1 with most image
    coordinates flagged, so ``solve`` says the model does not fit and exits 4 (COLMAP's
    case: tests/io/test_colmap_objective.py)."""
    from orientviz.cli import main

    rng = np.random.default_rng(4)
    pts = rng.uniform([-5, -5, -2], [5, 5, 2], (60, 3))
    X0 = np.array([[-6, 0.0, 30.0], [6, 0.1, 30.0], [0.0, -6, 31.0], [0.1, 6, 29.0], [0, 0, 30]])
    bal = _bal(tmp_path / "d.bal", X0, pts)
    lines = bal.read_text().splitlines()
    for i in range(1, 1 + len(X0) * len(pts)):  # pixels with k1 = 3 (r in units of f)
        c, p, x, y = lines[i].split()
        d = 1 + 3.0 * (float(x) ** 2 + float(y) ** 2) / 1000.0**2
        lines[i] = f"{c} {p} {float(x) * d:.6f} {float(y) * d:.6f}"
    bal.write_text("\n".join(lines) + "\n")
    out = tmp_path / "d.json"
    assert main(["import-bal", str(bal), "--fix-lens", "-o", str(out)]) == 0
    capsys.readouterr()
    # the iteration limit reached first (exit 3): the message says the model does not fit
    assert main(["solve", str(out), "--free"]) == 3
    assert "BUT THE MODEL DOES NOT FIT THE DATA" in capsys.readouterr().err
    assert main(["solve", str(out), "--free", "--max-iter", "200"]) == 4
    said = capsys.readouterr()
    assert "the model does not fit the data" in said.out and "lens distortion" in said.err
    # a pixel file: its lens held at import can be wrong, a pixel size cannot
    assert "--fix-lens" in said.err and "pixel size" not in said.err


def test_solving_an_import_without_a_datum_names_both_ways(tmp_path, capsys):
    """``solve`` of a reconstruction without ``--free``: exit 3, the message names
    ``--free`` and ``--fix`` and speaks of shifts, rotations and scale, not of
    planimetric and height control; an aerial block keeps its control advice."""
    import json

    from orientviz.cli import main
    from orientviz.io.datasets import dataset_path

    rng = np.random.default_rng(4)
    pts = rng.uniform([-5, -2, -5], [5, 2, 5], (30, 3))
    X0 = np.array([[-6, 30.0, 0.0], [6, 30.0, 0.1], [0.0, 31.0, -6]])
    bal = _bal(tmp_path / "m.bal", X0, pts, rotvec=(np.pi / 2, 0.0, 0.0))  # looking along −Y
    out = tmp_path / "m.json"
    assert main(["import-bal", str(bal), "-o", str(out)]) == 0
    capsys.readouterr()
    assert main(["solve", str(out)]) == 3
    err = capsys.readouterr().err
    assert f"orientviz solve {out} --free" in err and "--fix IMAGE --fix IMAGE2:X0" in err
    assert "the 3 shifts, the 3 rotations and the scale" in err
    assert "planimetric" not in err and "height" not in err and "tilt" not in err
    doc = json.loads(dataset_path("block_strip").read_text(encoding="utf-8"))
    for p in doc["points"]:  # an aerial strip without its control
        if p["role"] == "control":
            p["role"] = "tie"
            p.pop("sigma", None)
    (tmp_path / "strip.json").write_text(json.dumps(doc), encoding="utf-8")
    assert main(["solve", str(tmp_path / "strip.json")]) == 3
    err = capsys.readouterr().err
    assert "≥ 2 planimetric control points" in err and "--free" in err


def test_a_reconstruction_looking_along_its_minus_z_is_not_told_of_heights(tmp_path, capsys):
    """A reconstruction's axes point anywhere: cameras that happen to look along −Z of
    its frame (BAL's Dubrovnik and Trafalgar problems do) are no aerial block. ``solve``
    without ``--free`` names the 3 shifts, rotations and the scale, not planimetric and
    height control (the file's length unit is "model")."""
    from orientviz.cli import main

    rng = np.random.default_rng(4)
    pts = rng.uniform([-5, -5, -2], [5, 5, 2], (30, 3))
    X0 = np.array([[-6, 0.0, 30.0], [6, 0.1, 30.0], [0.0, -6, 31.0]])
    bal = _bal(tmp_path / "d.bal", X0, pts)  # R = I: every camera looks along −Z
    out = tmp_path / "d.json"
    assert main(["import-bal", str(bal), "-o", str(out)]) == 0
    capsys.readouterr()
    assert main(["solve", str(out)]) == 3
    err = capsys.readouterr().err
    assert "the 3 shifts, the 3 rotations and the scale" in err and "--free" in err
    assert "planimetric" not in err and "height" not in err and "tilt" not in err


def test_the_shipped_colmap_model_imports_by_name(tmp_path, monkeypatch, capsys):
    """`import-colmap axe`, as `import-bal ladybug`: the shipped model where no such folder is."""
    import json

    from orientviz.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["import-colmap", "axe", "-o", "axe.json"]) == 0
    doc = json.loads((tmp_path / "axe.json").read_text(encoding="utf-8"))
    assert len(doc["images"]["id"]) == 52 and "--free" in capsys.readouterr().out
    assert main(["import-colmap", "nothing-here", "-o", "x.json"]) == 2


def test_an_imported_pixel_model_is_not_told_of_a_pixel_size(tmp_path, capsys):
    """`import-bal` / `import-colmap` of a model in pixels: neither file has a pixel size, so
    the summary does not give one (it said '(pixel size 0.01 mm)', a nominal number the user
    never set); the datum hint's example reads as options, not as an ':X0:' syntax."""
    from orientviz.cli import main
    from orientviz.io.bal import write_bal
    from orientviz.io.colmap import write_colmap

    block = ov.simulate_block(1, 5, rng=7, control="full").block
    write_colmap(block, tmp_path / "sparse", pixel_size_mm=PIXEL_MM)
    write_bal(block, tmp_path / "p.bal", pixel_size_mm=PIXEL_MM)
    for cmd in (["import-colmap", str(tmp_path / "sparse")], ["import-bal", str(tmp_path / "p.bal")]):
        capsys.readouterr()
        assert main([*cmd, "-o", str(tmp_path / "m.json")]) == 0
        summary, hint = capsys.readouterr().out.splitlines()[:2]
        assert "(image coordinates in px)" in summary and "pixel size" not in summary
        assert ":X0 — one image and the scale" in hint and ":X0:" not in hint
