"""Problem files of kind ``radar``: round trip, schema, solve, bad input."""

import json
from importlib import resources

import numpy as np
import pytest

import orientviz as ov
from orientviz.io.jsonio import validator_for
from orientviz.io.kinds.radar import radar_problem_from_geier
from orientviz.io.problem import dumps_problem, loads_problem
from orientviz.io.registry import available_kinds, get_kind
from orientviz.radar import geier1973 as G
from orientviz.radar.data import DATASET
from orientviz.radar.orientation import calibrate

EXAMPLES = ["fig7_calibration_problem.json", "fig7_relative_problem.json"]


def _path(name):
    return resources.files("orientviz").joinpath(f"{DATASET}/{name}")


def test_kind_is_registered():
    assert "radar" in available_kinds()
    assert get_kind("radar").methods[0] == "calibration"


@pytest.mark.parametrize("name", EXAMPLES)
def test_example_round_trips_in_both_forms(name):
    text = _path(name).read_text(encoding="utf-8")
    p = ov.load_problem(str(_path(name)))
    assert dumps_problem(p) == text
    columnar = dumps_problem(p, columnar=True)
    back = loads_problem(columnar, "columnar.json")
    assert dumps_problem(back, columnar=False) == dumps_problem(p, columnar=False)
    for doc in (json.loads(text), json.loads(columnar)):
        assert list(validator_for("radar.json").iter_errors(doc)) == []


def test_solve_equals_the_library_call():
    p = ov.load_problem(str(_path("fig7_calibration_problem.json")))
    sol = get_kind("radar").solve(p, None)
    A = G.approximations()[2]
    direct = calibrate(
        G.points("fig7"),
        G.image_coordinates("fig7", 2),
        G.images()[2].with_(x0=A.x0, y0=A.y0, h=A.h, m=A.m, kappa=G.alpha0_approx()),
    )
    np.testing.assert_allclose(sol.adjustment.x, direct.x, rtol=0, atol=1e-9)
    d = sol.as_dict()
    assert d["redundancy"] == 45 and d["parameters"][0]["name"] == "x0"


def test_relative_problem_solves():
    p = ov.load_problem(str(_path("fig7_relative_problem.json")))
    sol = get_kind("radar").solve(p, None)
    assert sol.adjustment.redundancy == 25 - 6 and sol.adjustment.converged
    assert len(sol.point_ids) == 25 and sol.xyz.shape == (25, 3)


@pytest.mark.parametrize(
    "mutate, where",
    [
        (lambda d: d["observations"][3].update(point="99"), "observations[3].point"),
        (lambda d: d["observations"][0].update(sigma=-1.0), "observations[0].sigma"),
        (lambda d: d.update(task="fly"), "task"),
        (lambda d: d["images"].append(dict(d["images"][0], id="x")), "images"),
        (lambda d: d["images"][0].update(m=0.0), "images/0/m"),
    ],
)
def test_bad_input_names_the_place(mutate, where):
    doc = radar_problem_from_geier("fig7", "calibration")
    mutate(doc)
    with pytest.raises(ov.InputError) as exc:
        loads_problem(json.dumps(doc), "bad.json")
    msg = str(exc.value)
    assert msg.startswith("bad.json") and where.split("[")[0].split("/")[0] in msg
