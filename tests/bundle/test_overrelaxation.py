"""A convex loss's tail step over-relaxed by the model's curvature ratio along an
established linear tail (:data:`orientviz.bundle.loop._steps.OVERRELAX_MIN_RATIO`)."""

from __future__ import annotations

import contextlib
import io

import numpy as np
import pytest

from orientviz.bundle.loop import _steps
from orientviz.cli import main
from orientviz.io.kinds.block import adjust_block, prepare
from orientviz.io.problem import load_problem

#: The module's threshold (the runs below patch it).
MIN_RATIO = _steps.OVERRELAX_MIN_RATIO


@pytest.fixture(scope="module")
def ladybug(tmp_path_factory):
    """The shipped Ladybug problem as ``import-bal`` writes it, prepared with a free datum."""
    path = tmp_path_factory.mktemp("lb") / "ladybug.json"
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        assert main(["import-bal", "ladybug", "-o", str(path)]) == 0
    return path


def _run(path, monkeypatch, min_ratio: float):
    """Ladybug with Huber, ftol 1e-13, at most 48 steps (a robust run: 4 × max_iter)."""
    monkeypatch.setattr(_steps, "OVERRELAX_MIN_RATIO", min_ratio)
    prob = load_problem(str(path))
    prob.options.update(free=True, robust="huber", ftol=1e-13, max_iter=12)
    block, _ = prepare(prob)
    adj, _ = adjust_block(prob, block, precision=False)
    return adj


def test_a_stiff_linear_tail_converges(ladybug, monkeypatch):
    """Ladybug's tight Huber run: from ~step 21 a point and the cameras creep along one mode
    (Σρ −5e-11 per step, 3 % less each step; the model's curvature along the steps ~300
    times the true one). With the curvature-ratio ω the run converges within 48 steps and
    ends below where ω = 1.5 throughout stands after as many steps, which has not
    converged. Fails without: the same run, not converged."""
    plain = _run(ladybug, monkeypatch, np.inf)
    fast = _run(ladybug, monkeypatch, MIN_RATIO)
    assert fast.converged and not plain.converged
    assert fast.history[-1].cost < plain.history[-1].cost


@pytest.mark.parametrize(
    "ratios, omega",
    [
        ((30.0, 32.0), 30.0),  # agreeing, both stiff: the smaller
        ((300.0, 310.0), _steps.OVERRELAX_MAX),  # capped
        ((30.0, 50.0), _steps.ROBUST_OVERRELAX),  # disagreeing
        ((5.0, 5.5), _steps.ROBUST_OVERRELAX),  # not stiff enough (DBAT's tails: 2–7)
        ((0.0, 30.0), _steps.ROBUST_OVERRELAX),  # one step without a ratio
        ((np.inf, np.inf), _steps.ROBUST_OVERRELAX),  # the true Σρ not convex along s
    ],
)
def test_the_overrelaxation_follows_two_agreeing_stiff_ratios(ratios, omega):
    steps = object.__new__(_steps.BundleSteps)
    steps._ratios = ratios
    assert steps._overrelaxation() == omega
