"""Textbook-sized problems: six points without start values, feet, degrees-minutes-seconds."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import orientviz as ov
from orientviz.cli import main
from orientviz.io.datasets import dataset_path
from orientviz.io.problem import LENGTH_UNITS, load_problem, parse_dms
from orientviz.io.solve import solve_problem
from orientviz.rotation import matrix_from_opk

C = 152.113  # mm
#: six von Gruber points on gently rolling ground (m) and the two true orientations
POINTS = np.array(
    [[0, 0, 105.0], [920, 0, 98], [0, 900, 112], [920, 900, 95], [0, -900, 101], [920, -900, 108]]
)
TRUE = {
    "L": (np.array([0.0, 0, 1620]), np.radians([0.3, -0.4, 1.2])),
    "R": (np.array([920.0, 15, 1605]), np.radians([-0.8, 0.6, -0.9])),
}


def _image_points() -> dict[str, np.ndarray]:
    out = {}
    for name, (X0, angles) in TRUE.items():
        d = (POINTS - X0) @ matrix_from_opk(*angles, "opk")  # Rᵀ (X − X0) per row
        out[name] = np.round(-C * d[:, :2] / d[:, 2:], 3)  # as a textbook prints them
    return out


def _six_point_block(path) -> None:
    xy = _image_points()
    doc = {
        "format": "orientviz/1", "kind": "block", "name": "six points",
        "units": {"length": "m", "image": "mm", "angle": "deg"}, "sequence": "opk",
        "options": {"image_sigma": 0.005, "free": True},
        "cameras": [{"id": "cam", "c": C, "x0": 0, "y0": 0, "format": [230, 230]}],
        "images": [{"id": "L", "camera": "cam"}, {"id": "R", "camera": "cam"}],
        "points": [{"id": str(j + 1), "role": "tie"} for j in range(6)],
        "observations": [
            {"image": im, "point": str(j + 1), "x": float(x), "y": float(y)}
            for im in ("L", "R") for j, (x, y) in enumerate(xy[im])
        ],
    }  # fmt: skip
    path.write_text(json.dumps(doc), encoding="utf-8")


def _true_relative() -> tuple[np.ndarray, np.ndarray]:
    """Rotation of R in L's image frame and the unit base in it."""
    RL, RR = (matrix_from_opk(*TRUE[k][1], "opk") for k in ("L", "R"))
    base = RL.T @ (TRUE["R"][0] - TRUE["L"][0])
    return RL.T @ RR, base / np.linalg.norm(base)


def test_a_six_point_pair_without_start_values_orients(tmp_path):
    path = tmp_path / "six.json"
    _six_point_block(path)
    sol = solve_problem(load_problem(path))
    assert sol.adjustment.converged and sol.adjustment.redundancy == 1
    k = {ident: i for i, ident in enumerate(sol.image_ids)}
    RL = matrix_from_opk(*sol.angles[k["L"]], "opk")
    RR = matrix_from_opk(*sol.angles[k["R"]], "opk")
    rel, base = _true_relative()
    # the model frame is the free network's: compare what it cannot change
    assert np.degrees(np.arccos(np.clip((np.trace(RL.T @ RR @ rel.T) - 1) / 2, -1, 1))) < 2e-3
    b = RL.T @ (sol.X0[k["R"]] - sol.X0[k["L"]])
    assert np.degrees(np.arccos(b @ base / np.linalg.norm(b))) < 5e-3


def test_the_pair_kind_gives_the_same_relative_orientation(tmp_path):
    xy = _image_points()
    doc = {
        "format": "orientviz/1", "kind": "pair", "units": {"length": "mm", "image": "mm",
        "angle": "deg"}, "sequence": "opk", "options": {"sigma": 0.005}, "camera": {"c": C},
        "points": [{"id": str(j + 1), "xl": float(a[0]), "yl": float(a[1]), "xr": float(b[0]),
                    "yr": float(b[1])} for j, (a, b) in enumerate(zip(xy["L"], xy["R"]))],
    }  # fmt: skip
    path = tmp_path / "pair.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    sol = solve_problem(load_problem(path))
    p = {q.name: q.value for q in sol.parameters}
    rel, _ = _true_relative()
    R = matrix_from_opk(p["omega"], p["phi"], p["kappa"], "opk")
    # the dependent pair's frame is the left image's, as the true relative rotation
    assert np.degrees(np.arccos(np.clip((np.trace(R @ rel.T) - 1) / 2, -1, 1))) < 2e-3


@pytest.mark.parametrize("unit", ["ft", "us-ft"])
def test_object_lengths_in_feet(tmp_path, capsys, unit):
    f = LENGTH_UNITS[unit]
    assert f == pytest.approx(0.3048 if unit == "ft" else 1200 / 3937, rel=1e-15)
    doc = json.loads(dataset_path("resection_example").read_text(encoding="utf-8"))
    doc["units"]["length"] = unit
    for p in doc["points"]:
        for k in "XYZ":
            p[k] = p[k] / f
    path = tmp_path / f"res_{unit}.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    metric = solve_problem(load_problem(dataset_path("resection_example")))
    feet = solve_problem(load_problem(path))
    assert np.allclose(feet.X0, metric.X0, atol=1e-6)  # internally metres either way
    assert main(["solve", str(path), "--report", str(tmp_path / "r.txt")]) == 0
    out = capsys.readouterr().out
    assert f"X0 Y0 Z0 ± σ [{unit}]" in out and "[m]" not in out
    X0_file = float(out.split(f"[{unit}], omega")[1].splitlines()[1].split()[1])
    assert X0_file == pytest.approx(metric.X0[0, 0] / f, abs=1e-3)
    report = (tmp_path / "r.txt").read_text(encoding="utf-8")
    assert f"X0 [{unit}]" in report and f"σX0 [{unit}]" in report and "[m]" not in report


@pytest.mark.parametrize(
    ("text", "degrees"),
    [("12°34'56.7\"", 12 + 34 / 60 + 56.7 / 3600), ("-0°05'00\"", -5 / 60),
     ("12 34 56.7", 12 + 34 / 60 + 56.7 / 3600), ("12d34m56.7s", 12 + 34 / 60 + 56.7 / 3600),
     ("7°", 7.0), ("1 30", 1.5)],
)  # fmt: skip
def test_parse_dms(text, degrees):
    assert parse_dms(text) == pytest.approx(degrees, abs=1e-12)


@pytest.mark.parametrize("text", ["12°61'00\"", "abc", "1°2'3\"4", ""])
def test_parse_dms_refuses(text):
    with pytest.raises(ValueError):
        parse_dms(text)


def _dms(deg: float) -> str:
    sign, deg = ("-" if deg < 0 else ""), abs(deg)
    d = int(deg)
    m = int((deg - d) * 60)
    s = (deg - d - m / 60) * 3600
    return f"{sign}{d}°{m:02d}'{s:09.6f}\""


def test_angles_in_degrees_minutes_seconds(tmp_path, capsys):
    doc = json.loads(dataset_path("block_strip").read_text(encoding="utf-8"))
    assert doc["units"]["angle"] == "gon"
    doc["units"]["angle"] = "dms"
    for im in doc["images"]:
        for k in ("omega", "phi", "kappa"):
            im[k] = _dms(im[k] * 0.9)  # gon → degrees, written as d°m's"
    path = tmp_path / "dms.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    given = load_problem(path).data.images.angles
    gon = load_problem(dataset_path("block_strip")).data.images.angles
    assert np.allclose(given, gon, atol=math.radians(1e-6 / 3600))
    assert main(["solve", str(path)]) == 0
    assert "angle deg" in capsys.readouterr().out  # read and reported as decimal degrees
    doc["images"][1]["phi"] = "1°75'00\""
    path.write_text(json.dumps(doc), encoding="utf-8")
    assert main(["solve", str(path)]) == 2
    err = capsys.readouterr().err
    assert "images[1].phi" in err and "below 60" in err


def test_the_front_door_reads_them_too(tmp_path):
    path = tmp_path / "six.json"
    _six_point_block(path)
    assert ov.load_problem(path).data.n_images == 2


def test_collinearity_method_is_the_two_image_bundle_and_parallax_is_close(tmp_path):
    """Kovarik's y-parallax estimator and the textbook collinearity method on noisy data."""
    from orientviz.orientation.relative import relative_orientation

    rng = np.random.default_rng(29)
    xy = {k: v + rng.normal(0.0, 0.004, v.shape) for k, v in _image_points().items()}
    col = relative_orientation(xy["L"], xy["R"], C, method="collinearity", b="mean")
    par = relative_orientation(xy["L"], xy["R"], C)
    assert col.method == "collinearity" and col.converged and col.redundancy == 1
    assert col.base == pytest.approx(float(np.mean(xy["L"][:, 0] - xy["R"][:, 0])))
    # the same data as a two-image block (free network): the bundle's relative orientation
    path = tmp_path / "noisy.json"
    _six_point_block(path)
    doc = json.loads(path.read_text(encoding="utf-8"))
    for o in doc["observations"]:
        o["x"], o["y"] = (float(v) for v in xy[o["image"]][int(o["point"]) - 1])
    path.write_text(json.dumps(doc), encoding="utf-8")
    sol = solve_problem(load_problem(path))
    k = {ident: i for i, ident in enumerate(sol.image_ids)}
    RL = matrix_from_opk(*sol.angles[k["L"]], "opk")
    rel_block = RL.T @ matrix_from_opk(*sol.angles[k["R"]], "opk")
    b_block = RL.T @ (sol.X0[k["R"]] - sol.X0[k["L"]])
    R_col = matrix_from_opk(*col.x[2:5], "opk")
    b_col = np.array([col.base, *col.x[:2]])
    assert np.abs(R_col - rel_block).max() < 1e-9  # the same estimator
    assert np.abs(b_col / np.linalg.norm(b_col) - b_block / np.linalg.norm(b_block)).max() < 1e-9
    # Kovarik's estimator weighs the same information differently: close, not equal
    R_par = matrix_from_opk(*par.x[2:5], "opk")
    gap = np.abs(R_par - R_col).max()
    assert 1e-9 < gap < 5 * np.sqrt(np.diag(par.cofactor)[2:5]).max() * par.sigma0 + 1e-6


def test_the_pair_kind_prints_the_model_points(tmp_path, capsys):
    xy = _image_points()
    doc = {
        "format": "orientviz/1", "kind": "pair", "units": {"length": "mm", "image": "mm",
        "angle": "deg"}, "sequence": "opk", "camera": {"c": C},
        "options": {"sigma": 0.005, "method": "collinearity", "base": "mean"},
        "points": [{"id": f"P{j + 1}", "xl": float(a[0]), "yl": float(a[1]), "xr": float(b[0]),
                    "yr": float(b[1])} for j, (a, b) in enumerate(zip(xy["L"], xy["R"]))],
    }  # fmt: skip
    path = tmp_path / "pair.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    assert main(["solve", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [p["id"] for p in out["points"]] == [f"P{j + 1}" for j in range(6)]
    assert all(p["role"] == "model" and p["Z"] < 0 and p["sigma"]["Z"] > 0 for p in out["points"])
    assert "collinearity" in out["method"]
    assert main(["solve", str(path)]) == 0
    text = capsys.readouterr().out
    assert "points (X Y Z ± σ [mm]):" in text and "base bx = the mean x-parallax" in text
