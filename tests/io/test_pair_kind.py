"""Problem files of kind ``pair``: example, round trips, solving, bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import orientviz as ov
from orientviz.cli import main
from orientviz.io.problem import dumps_problem, loads_problem
from orientviz.io.registry import get_kind

HERE = Path(__file__).resolve().parents[2] / "src" / "orientviz" / "datasets" / "pair"
EXAMPLE = HERE / "pair_example.json"


def _doc():
    return json.loads(EXAMPLE.read_text(encoding="utf-8"))


def test_example_is_reproducible(tmp_path):
    from orientviz.datasets.make_pair_example import make

    out = make(tmp_path / "pair.json")
    assert out.read_text(encoding="utf-8") == EXAMPLE.read_text(encoding="utf-8")


def test_round_trip_both_forms():
    text = EXAMPLE.read_text(encoding="utf-8")
    problem = ov.load_problem(EXAMPLE)
    assert dumps_problem(problem) == text
    columnar = dumps_problem(problem, columnar=True)
    back = loads_problem(columnar, "columnar.json")
    assert dumps_problem(back, columnar=False) == text


def test_solve_recovers_the_truth_within_its_precision():
    truth = json.loads((HERE / "MANIFEST.json").read_text())["datasets"][0]["truth"]
    sol = ov.solve_problem(ov.load_problem(EXAMPLE))
    p = {q.name: q for q in sol.parameters}
    f = sol.factor("angle")
    # 3 µm image noise, 25 points: every element within 4 σ of the simulated truth
    for name, key, scale in (("by", "by_mm", 1e-3), ("bz", "bz_mm", 1e-3),
                             ("omega", "omega_c", None), ("phi", "phi_c", None), ("kappa", "kappa_c", None)):  # fmt: skip
        val = p[name].value / scale if scale else p[name].value * f
        sig = p[name].sigma / scale if scale else p[name].sigma * f
        assert abs(val - truth[key]) < 4 * sig, (name, val, truth[key], sig)
    assert 0.6 < sol.adjustment.sigma0 < 1.5


def test_essential_route_and_independent_elements():
    doc = _doc()
    doc["options"]["route"] = "essential"
    a = ov.solve_problem(loads_problem(json.dumps(doc), "e.json"))
    b = ov.solve_problem(ov.load_problem(EXAMPLE))
    np.testing.assert_allclose(a.adjustment.x, b.adjustment.x, atol=1e-9)
    doc = _doc()
    doc["options"]["elements"] = "independent"
    c = ov.solve_problem(loads_problem(json.dumps(doc), "i.json"))
    assert [q.name for q in c.parameters][1:] == ["phi1", "kappa1", "phi2", "omega2", "kappa2"]
    # same five degrees of freedom, but the y-parallax is measured in a model frame
    # turned by the ~1.5 gon of the left image: σ0 agrees to second order (~1e-4)
    assert c.adjustment.sigma0 == pytest.approx(b.adjustment.sigma0, rel=1e-3)


def test_cli_solve(capsys):
    assert main(["solve", str(EXAMPLE), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["kind"] == "pair" and out["converged"]


@pytest.mark.parametrize(
    "mutate, where",
    [
        (lambda d: d.update(points=d["points"][:4]), "points"),
        (lambda d: d["points"][3].update(id="P1"), "points[3].id"),
        (lambda d: d.update(approx={"omega2": 1.0}), "approx.omega2"),
        (lambda d: d.pop("camera"), "camera"),
        (lambda d: d["points"][0].update(zl=1.0), "points/0"),
    ],
)
def test_bad_input_names_the_place(mutate, where):
    doc = _doc()
    mutate(doc)
    with pytest.raises(ov.InputError) as exc:
        ov.solve_problem(loads_problem(json.dumps(doc), "bad.json"))
    assert "bad.json" in str(exc.value)
    assert where.split("/")[0].split("[")[0].split(".")[0] in str(exc.value)


def test_kind_registered():
    assert get_kind("pair").schema == "pair.json"
