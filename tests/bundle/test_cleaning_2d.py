"""Block cleaning with the 2-D test: detection, false alarms, check rays, the log."""

import numpy as np
import pytest
from scipy.special import chdtr

import orientviz as ov
from orientviz.adjust.gross import noncentrality
from orientviz.adjust.gross2d import critical_values_2d, noncentrality_2d, statistic_2d
from orientviz.block import CHECK, TIE
from orientviz.bundle import ExteriorPairs, bundle_solver, ray_labels
from orientviz.bundle._cleaning import _check_ray_tests


@pytest.fixture(scope="module")
def sim():
    # 16 blunders of 20-250 µm (4-50 σ) among ~1400 rays; 20 check points
    return ov.simulate_block(3, 8, rng=7, gross={"count": 16, "size_mm": (0.02, 0.25)}, n_check=20)


@pytest.fixture(scope="module")
def clean():
    return ov.simulate_block(4, 10, rng=11, n_check=30)


def _lambda(sim):
    """Non-centrality of each injected blunder in the 2-D test (exact, error-free geometry)."""
    n = sim.block.n_observations
    ref = bundle_solver(sim.truth)(np.ones(2 * n))
    idx = sim.info["gross"]["index"]
    r = ref.redundancy_numbers.reshape(n, 2)[idx]
    s = sim.block.observations.sigma[idx]
    return idx, noncentrality_2d(sim.info["gross"]["error_mm"], s, r, ref.redundancy_xy[idx])


@pytest.mark.parametrize("fast", [True, False])
def test_every_testable_blunder_is_removed(sim, fast):
    idx, lam = _lambda(sim)
    testable = idx[lam >= noncentrality() ** 2]
    assert testable.size >= 10  # the test is not vacuous
    c = ov.clean_block(sim.block, "snooping", fast=fast)
    kept = c.adjustment.subset.kept_rays
    assert not kept[testable].any()
    # after cleaning the data fit the 5 µm noise again
    assert c.adjustment.sigma0 == pytest.approx(1.0, abs=0.06)
    # good rays lost: at most the partners of 2-ray points plus a few chance rejections
    good = np.ones(kept.size, bool)
    good[idx] = False
    assert (~kept & good).sum() <= 0.01 * good.sum()


def test_log_names_each_removed_ray_with_its_statistic(sim):
    c = ov.clean_block(sim.block, "snooping")
    labels = ray_labels(sim.block)
    crit = critical_values_2d()
    elim = [e for e in c.log if e.action == "eliminated"]
    assert sorted(e.observation for e in elim) == sorted(c.eliminated.tolist())
    for e in elim:
        assert e.label == labels[e.observation]
        assert f"T = {e.w**2:.1f}" in e.reason
        assert e.w**2 > min(crit[1], crit[2])
    assert c.log[-1].action == "stopped"
    assert all(labels[e.observation] in c.table() for e in elim)


def test_error_free_block_false_alarms_within_binomial_bound(clean):
    b = clean.block
    n = b.n_observations
    adj = bundle_solver(b)(np.ones(2 * n))
    r = adj.redundancy_numbers.reshape(n, 2)
    z = np.nan_to_num(adj.normalized_residuals).reshape(n, 2) * np.sqrt(r)
    T, dof = statistic_2d(z, r, adj.redundancy_xy)
    # calibration: T is χ² with 1 or 2 dof (means 1 and 2; sd of the mean ≈ 0.05-0.1)
    assert T[dof == 2].mean() == pytest.approx(2.0, abs=0.2)
    assert T[dof == 1].mean() == pytest.approx(1.0, abs=0.2)
    crit = critical_values_2d()
    c = ov.clean_block(b, "snooping")
    rejected = sum(1 for e in c.log if e.action == "eliminated")
    # tests made: one per ray (the two rays of a 2-ray point give the same statistic)
    p = 1.0 - chdtr(2, crit[2])  # the larger of the two levels (0.28 %)
    tests = n
    mean, sd = tests * p, np.sqrt(tests * p * (1 - p))
    assert rejected <= mean + 4 * sd  # ≈ 1e-4 one-sided
    excluded = (~c.adjustment.subset.kept_rays).sum()
    assert excluded <= 2 * (mean + 4 * sd)  # a 2-ray point takes its second ray along


def test_check_point_rays_are_tested_in_their_intersection(sim):
    b = sim.block
    n = b.n_observations
    solve = bundle_solver(b)
    adj = solve(np.ones(2 * n))
    o = b.observations
    chk = b.points.role[o.point] == CHECK
    r = adj.redundancy_numbers.reshape(n, 2)
    assert np.isfinite(adj.normalized_residuals.reshape(n, 2)[chk & (r > 0).all(1)]).all()
    assert ((r[chk] >= 0) & (r[chk] <= 1)).all()
    # with error-free orientations (Q_ee = 0) the test is that of a forward intersection
    # of k rays: redundancy numbers sum to 2k − 3 per check point
    keys, blocks = adj.exterior_pairs.keys, adj.exterior_pairs.blocks
    rn, wn, rxy = np.zeros((n, 2)), np.full((n, 2), np.nan), np.zeros(n)
    v = adj.residuals.reshape(n, 2)
    _check_ray_tests(
        b, adj, np.arange(n), v, o.sigma, rn, wn, rxy, chk, ExteriorPairs(keys, 0 * blocks)
    )
    for p in np.unique(o.point[chk]):
        rays = o.point == p
        assert rn[rays].sum() == pytest.approx(2 * rays.sum() - 3, abs=1e-6)
    # the orientations' errors enlarge the residuals' variance: smaller statistics
    T0, _ = statistic_2d((np.nan_to_num(wn) * np.sqrt(rn))[chk], rn[chk], rxy[chk])
    z = np.nan_to_num(adj.normalized_residuals).reshape(n, 2) * np.sqrt(r)
    T1, _ = statistic_2d(z[chk], r[chk], adj.redundancy_xy[chk])
    assert T1.sum() < T0.sum()
    # local redundancy (orientations held fixed) bounds the exact one from above
    loc = solve(np.ones(2 * n), "local")
    tie = b.points.role[o.point] == TIE
    rl = loc.redundancy_numbers.reshape(n, 2)
    assert (rl[tie] >= r[tie] - 1e-9).all()
    assert np.mean(rl[tie] - r[tie]) < 0.1
    # a blunder on a 6-ray check point is found
    p = [q for q in np.unique(o.point[chk]) if (o.point == q).sum() >= 4][0]
    j = np.flatnonzero(o.point == p)[1]
    bad = b.copy()
    bad.observations.xy[j] += [0.06, -0.04]
    c = ov.clean_block(bad, "snooping")
    assert not c.adjustment.subset.kept_rays[j]
    assert ov.clean_block(bad, "snooping", check_rays=False).adjustment.subset.kept_rays[j]
