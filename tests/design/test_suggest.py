"""The suggested control point against brute force on small blocks."""

from __future__ import annotations

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

import orientviz as ov
from orientviz.design import (
    FlightDesign,
    LiveDesign,
    assess_block,
    design_block,
    set_control,
    suggest_control,
)
from orientviz.design._suggest import worst


@pytest.fixture(scope="module", autouse=True)
def _one_thread():
    with threadpool_limits(1, "blas"):
        yield


@pytest.fixture(scope="module")
def base():
    return design_block(FlightDesign(strips=2, images_per_strip=7, control="corners"))


def _brute(block, spec, cands, criterion, sigma=0.02):
    out = []
    for j in cands:
        _, q = assess_block(set_control(block, int(j), (sigma,) * 3), spec)
        if criterion == "external":
            out.append(q.summary["external_max"])
        else:
            out.append(worst(q.point_sigma, q.control, criterion))
    return np.asarray(out)


@pytest.mark.parametrize("criterion", ["sigma_z", "sigma_xy"])
def test_suggestion_is_the_brute_force_best(base, criterion):
    block, spec = base
    live = LiveDesign(block, spec)
    # one change already made: the suggestion must work on the current design
    tie = np.flatnonzero(block.points.role == ov.TIE)
    live.set_control(int(tie[0]), (np.nan, np.nan, 0.05))
    sug = suggest_control(live, criterion=criterion)
    assert np.array_equal(sug.candidates, np.flatnonzero(live.block.points.role == ov.TIE))
    brute = _brute(live.block, spec, sug.candidates, criterion)
    np.testing.assert_allclose(sug.values, brute, rtol=1e-5)
    # the best by brute force (symmetric points may tie: equal up to rounding)
    assert brute[list(sug.candidates).index(sug.point)] <= brute.min() * (1 + 1e-6)
    assert sug.after < sug.before and sug.gain > 0
    assert sug.point_id in sug.describe()
    # accepting it gives the promised value
    q = live.add_control(sug.point, 0.02)
    assert worst(q.point_sigma, q.control, criterion) == pytest.approx(sug.after, rel=1e-5)


def test_external_reliability_suggestion_is_the_brute_force_best(base):
    block, spec = base
    live = LiveDesign(block, spec)
    tie = np.flatnonzero(block.points.role == ov.TIE)
    cands = tie[::3]
    n_hist = len(live.history)
    sug = suggest_control(live, criterion="external", candidates=cands)
    assert len(live.history) == n_hist and not live.changes  # tried and taken back
    brute = _brute(block, spec, cands, "external")
    np.testing.assert_allclose(sug.values, brute, rtol=1e-5)
    assert brute[list(cands).index(sug.point)] <= brute.min() * (1 + 1e-6)
