"""Geier (1973) Fig. 8: a genuine reproduction test.

The paper's printed values (shipped in fig8_paper.json) are the expected data; the
tolerance is the paper's printed rounding (half a unit of the last printed digit).
Calibration and the joint six-parameter exterior orientation reproduce once the
conventions (gon, R = R_φ R_ω R_κ, the surfaces) and the stopping rule are used.
"""

import numpy as np
import pytest

from orientviz.radar import fig8
from orientviz.radar.data import build, load_fig7, load_fig8_paper, load_surface, load_surfaces
from orientviz.radar.geier1973 import COLUMNS

PAPER = load_fig8_paper()
DEC = {"m": 2, "1e-6": 0, "cc": 0, "1": 3}


def _half_unit(unit):
    return 0.5 * 10.0 ** -DEC[unit] + 1e-9


@pytest.fixture(scope="module")
def results():
    return {c: fig8.run_surface(c, tasks=("calibration", "exterior")) for c in COLUMNS}


@pytest.mark.parametrize("column", COLUMNS)
def test_calibration_reproduces_fig8(results, column):
    j = PAPER["columns"].index(column)
    out = results[column]["calibration"]
    for q, values in PAPER["tasks"]["calibration"].items():
        unit = PAPER["units"][q]
        assert abs(round(out.values[q], DEC[unit]) - values[j]) < _half_unit(unit), (
            q,
            out.values[q],
        )


@pytest.mark.parametrize("column", COLUMNS)
def test_exterior_reproduces_fig8(results, column):
    j = PAPER["columns"].index(column)
    out = results[column]["exterior"]
    for q, values in PAPER["tasks"]["exterior"].items():
        unit = PAPER["units"][q]
        if column == "cyl_x300_concave" and q == "m0":
            # documented exception: orientviz 0.3254, paper 0.32 (docs/geier_conventions.md)
            assert abs(out.values[q] - values[j]) < 0.006
            continue
        assert abs(round(out.values[q], DEC[unit]) - values[j]) < _half_unit(unit), (
            q,
            out.values[q],
        )


def test_calibration_needs_the_stopping_rule_in_two_columns():
    # iterating to convergence loses columns 8 and 10 (the paper stopped after one step)
    conv = {c: fig8.run_surface(c, tasks=("calibration",), stopping="converge") for c in COLUMNS}
    bad = []
    for c in COLUMNS:
        j = PAPER["columns"].index(c)
        for q, values in PAPER["tasks"]["calibration"].items():
            unit = PAPER["units"][q]
            v = conv[c]["calibration"].values[q]
            if abs(round(v, DEC[unit]) - values[j]) >= _half_unit(unit):
                bad.append(c)
                break
    assert bad == ["cyl_x150_concave", "cyl_x300_concave"]


def test_image2_rounding_is_unambiguous():
    # image 2 (calibration, exterior orientation): no exact coordinate within 0.5 mm of a
    # half metre, so any arithmetic of 1973 (≥ 7 significant digits at ≤ 7e4 m) rounded
    # as orientviz does. Images 1 and 3 do have values within 0.1-0.7 mm of a half
    # (documented in docs/geier_conventions.md).
    for c in COLUMNS:
        _, xy = load_surface(c, 2, rounded=False)
        assert np.abs(xy - np.floor(xy) - 0.5).min() > 5e-4, c


def test_shipped_dataset_equals_a_fresh_build():
    fresh = build()
    assert fresh["fig7.json"] == load_fig7()
    shipped = load_surfaces()
    for c in COLUMNS:
        for i in ("1", "2", "3"):
            a = np.array(shipped["surfaces"][c]["images"][i]["rounded"])
            b = np.array(fresh["surfaces.json"]["surfaces"][c]["images"][i]["rounded"])
            np.testing.assert_array_equal(a, b)


def test_reproduce_registry_rows():
    from orientviz.reproduce import run

    rows = run("geier", draws=0)
    summary = {r.task: (r.paper, r.orientviz) for r in rows if r.case == "all columns"}
    assert summary["1 calibration (image 2)"] == (60, 60)
    assert summary["2c exterior orientation, 6 jointly (image 2)"] == (70, 69)
    singular = [r for r in rows if r.paper == "singular matrix"]
    assert len(singular) == 7 and all("Kugel 150" in r.case for r in singular)
