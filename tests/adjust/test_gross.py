"""Gross-error detection on small dense problems (line fit, space resection)."""

import numpy as np
import pytest

from orientviz.adjust import gauss_newton
from orientviz.adjust.gross import (
    CleaningBreakdown,
    critical_value,
    engine_solver,
    noncentrality,
    redundancy_numbers,
    reliability,
)
from orientviz.adjust.robust import rerun_cleaning, robust_adjust, robust_weights
from orientviz.adjust.snooping import data_snooping
from orientviz.camera import collinearity_jacobian
from orientviz.errors import InputError

T = np.linspace(0.0, 10.0, 40)
SIGMA = 0.01


def _line(x):
    return x[0] + x[1] * T, np.column_stack([np.ones_like(T), T])


def _data(rng, blunders=()):
    l = 1.0 + 0.5 * T + rng.normal(0.0, SIGMA, T.size)
    for i, b in blunders:
        l[i] += b
    return l


def test_test_values():
    # textbook values of Baarda's B-method: alpha0 = 0.1 %, beta0 = 80 %
    assert critical_value(0.001) == pytest.approx(3.2905, abs=1e-4)
    assert noncentrality(0.001, 0.80) == pytest.approx(4.1321, abs=1e-4)
    assert critical_value(0.05) == pytest.approx(1.96, abs=1e-3)
    with pytest.raises(InputError):
        critical_value(1.5)


def test_redundancy_numbers_match_engine_and_sum_to_redundancy():
    rng = np.random.default_rng(0)
    adj = gauss_newton(_line, [0.0, 0.0], _data(rng), SIGMA)
    r = redundancy_numbers(_line(adj.x)[1], SIGMA)
    np.testing.assert_allclose(r, adj.redundancy_numbers, atol=1e-12)
    assert r.sum() == pytest.approx(T.size - 2, abs=1e-9)


@pytest.mark.parametrize("i", [0, 17, 39])
def test_mdb_gives_w_equal_delta0_and_effect_exactly(i):
    """Noise-free line with a bias of exactly one MDB: |w_i| = δ0, x̂ − x = effect_i."""
    l0 = 1.0 + 0.5 * T
    adj0 = gauss_newton(_line, [0.0, 0.0], l0 + np.linspace(0, 1e-3, T.size) ** 2, SIGMA)
    rel = reliability(adj0, _line(adj0.x)[1])
    l = l0.copy()
    l[i] += rel.mdb[i]
    adj = gauss_newton(_line, [0.0, 0.0], l, SIGMA)
    assert abs(adj.normalized_residuals[i]) == pytest.approx(rel.delta0, rel=1e-9)
    np.testing.assert_allclose(adj.x - [1.0, 0.5], rel.effect[i], atol=1e-12)
    # external reliability: the effect measured in the metric of N is δ̄0
    N = np.linalg.inv(adj.cofactor)
    dx = rel.effect[i]
    assert np.sqrt(dx @ N @ dx) == pytest.approx(rel.external[i], rel=1e-9)
    # end points have smaller redundancy -> larger MDB
    assert rel.mdb[0] > rel.mdb[20]


def test_data_snooping_finds_planted_blunders():
    rng = np.random.default_rng(42)
    planted = [(5, 0.08), (22, -0.12), (33, 0.06)]  # 6-12 sigma
    l = _data(rng, planted)
    solve = engine_solver(_line, [0.0, 0.0], l, SIGMA)
    res = data_snooping(solve, T.size)
    assert sorted(res.eliminated.tolist()) == [5, 22, 33]
    # largest error first: it had the largest |w| in the first adjustment
    assert res.eliminated[0] == 22
    assert res.adjustments == 4
    assert [e.action for e in res.log] == ["eliminated"] * 3 + ["stopped"]
    keep = np.setdiff1d(np.arange(T.size), [5, 22, 33])
    sub = lambda x: tuple(a[keep] for a in _line(x))
    clean = gauss_newton(sub, [0.0, 0.0], l[keep], SIGMA)
    np.testing.assert_allclose(res.adjustment.x, clean.x, atol=1e-10)
    assert res.adjustment.redundancy == T.size - 3 - 2
    # the eliminated observations still show their (large) residuals
    assert abs(res.adjustment.residuals[22]) == pytest.approx(0.12, abs=5 * SIGMA)
    assert "eliminated" in res.table()


@pytest.mark.parametrize("method", ["huber", "danish"])
def test_robust_finds_the_same_blunders(method):
    rng = np.random.default_rng(42)
    l = _data(rng, [(5, 0.08), (22, -0.12), (33, 0.06)])
    res = robust_adjust(engine_solver(_line, [0.0, 0.0], l, SIGMA), T.size, method=method)
    assert sorted(res.eliminated.tolist()) == [5, 22, 33]
    assert res.weights[[5, 22, 33]].sum() == 0.0 and res.weights.sum() == T.size - 3
    assert res.method == f"robust ({method})"


def test_robust_weight_functions():
    e = np.array([0.0, 1.0, 3.0, 6.0, 30.0])
    np.testing.assert_allclose(robust_weights(e, "huber"), [1, 1, 0.5, 0.25, 0.05])
    d = robust_weights(e, "danish")
    assert d[0] == d[1] == d[2] == 1.0 and d[3] == pytest.approx(np.exp(-3.0))
    assert d[4] < 1e-40  # a 30-sigma error has no influence left
    with pytest.raises(InputError, match="unknown robust method"):
        robust_weights(e, "tukey")


def test_breakdown_keeps_the_log():
    rng = np.random.default_rng(3)
    bad = [(i, 0.5 * (-1) ** i) for i in range(0, 40, 2)]  # half of the data are blunders
    l = _data(rng, bad)
    with pytest.raises(CleaningBreakdown, match="too contaminated") as info:
        data_snooping(engine_solver(_line, [0.0, 0.0], l, SIGMA), T.size)
    assert len(info.value.log) >= 8
    assert info.value.log[-1].action == "breakdown"
    assert (info.value.weights == 0).sum() == 8  # 20 % of 40 eliminated before stopping


def _resection_problem(rng, blunder=None):
    """A vertical image (c = 153 mm) of 12 known points; 6 exterior parameters."""
    pts = np.column_stack(
        [rng.uniform(-600, 600, 12), rng.uniform(-600, 600, 12), rng.uniform(0, 80, 12)]
    )
    truth = np.array([10.0, -20.0, 1500.0, 0.01, -0.02, 0.3])

    def model(x):
        xy, Je, _, _ = collinearity_jacobian(pts, x[:3], x[3:], 153.0)
        return xy.reshape(-1), Je.reshape(-1, 6)

    l = model(truth)[0] + rng.normal(0.0, 0.005, 24)
    if blunder is not None:
        l[blunder[0]] += blunder[1]
    return model, l, truth


def test_resection_blunder_is_eliminated_per_point():
    rng = np.random.default_rng(7)
    model, l, truth = _resection_problem(rng, blunder=(9, 0.060))  # point 4, y, 12 sigma
    x0 = truth + [50, -40, 30, 0.02, 0.02, -0.05]
    solve = engine_solver(model, x0, l, 0.005, names=["X0", "Y0", "Z0", "om", "ph", "ka"])
    res = data_snooping(solve, 24, groups=np.repeat(np.arange(12), 2))
    assert res.eliminated.tolist() == [4]
    assert res.weights[8] == res.weights[9] == 0.0
    # position back to noise level: with 11 points and σ = 5 µm the centre is good to ~0.1 m
    assert np.abs(res.adjustment.x[:3] - truth[:3]).max() < 0.5


def test_reruns_need_several_runs():
    """Raw residuals > 3 σ̂0 with several blunders: masking makes it take reruns."""
    rng = np.random.default_rng(11)
    planted = [(3, 0.30), (4, 0.06), (20, -0.07), (36, 0.05)]
    l = _data(rng, planted)
    res = rerun_cleaning(engine_solver(_line, [0.0, 0.0], l, SIGMA), T.size)
    assert {3, 4, 20, 36} <= set(res.eliminated.tolist())
    assert res.adjustments >= 3  # the big error hides the small ones in the first run
