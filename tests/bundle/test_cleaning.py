"""Automatic cleaning of a simulated block with the bundle (data snooping, robust, reruns)."""

import numpy as np
import pytest

import orientviz as ov
from orientviz.adjust.gross import CleaningBreakdown
from orientviz.bundle import bundle_solver, cleaned_block


@pytest.fixture(scope="module")
def sim():
    # 12 blunders of 30-250 µm (6-50 σ) among ~1400 rays
    return ov.simulate_block(3, 8, rng=4, gross={"count": 12, "size_mm": (0.03, 0.25)}, n_check=20)


def test_solver_reports_all_rays_and_drops_lonely_points(sim):
    b = sim.block
    n = b.n_observations
    solve = bundle_solver(b)
    full = solve(np.ones(2 * n))
    plain = ov.bundle_adjust(b)
    np.testing.assert_allclose(full.residuals, plain.residuals[: 2 * n], atol=1e-9)
    w = np.ones((n, 2))
    # a 2-ray tie point: eliminating one ray takes the whole point out
    pt = np.flatnonzero((b.rays_per_point() == 2) & (b.points.role == 0))[0]
    rays = np.flatnonzero(b.observations.point == pt)
    w[rays[0]] = 0.0
    adj = solve(w.reshape(-1))
    kept = adj.subset.kept_rays
    assert not kept[rays].any() and kept.sum() == n - 2
    assert np.isnan(adj.normalized_residuals.reshape(n, 2)[rays]).all()
    assert adj.redundancy_numbers.reshape(n, 2)[rays].sum() == 0.0


@pytest.mark.parametrize("one", [True, False])
def test_data_snooping_removes_the_blunders(sim, one):
    g = set(sim.info["gross"]["index"].tolist())
    c = ov.clean_block(sim.block, "snooping", one_at_a_time=one)
    excluded = set(np.flatnonzero(~c.adjustment.subset.kept_rays).tolist())
    # one blunder (47 µm, in a weakly controlled direction) stays below k for this seed
    assert len(g - excluded) <= 1
    # the rest of the data is clean: σ0 back to the 5 µm noise (±3 % for ~1400 rays)
    assert c.adjustment.sigma0 == pytest.approx(1.0, abs=0.06)
    assert c.log[-1].action == "stopped"
    assert all(e.label.count("/") == 1 for e in c.log if e.action == "eliminated")
    if not one:  # several rays per adjustment: far fewer adjustments
        exact = ov.clean_block(sim.block, "snooping", fast=False)  # every round exact
        assert exact.adjustments <= 6
    clean = cleaned_block(sim.block, c)
    assert clean.n_observations == int(c.adjustment.subset.kept_rays.sum())


@pytest.mark.slow
def test_robust_and_reruns_run_and_log(sim):
    g = set(sim.info["gross"]["index"].tolist())
    for method in ("danish", "reruns"):
        c = ov.clean_block(sim.block, method)
        excluded = set(np.flatnonzero(~c.adjustment.subset.kept_rays).tolist())
        assert len(g - excluded) <= 1
        assert c.adjustment.sigma0 < 1.1


def test_bad_method_and_breakdown():
    sim = ov.simulate_block(2, 4, rng=1, extra=None, gross={"fraction": 0.4, "size_mm": 0.2})
    with pytest.raises(ov.InputError, match="unknown cleaning method"):
        ov.clean_block(sim.block, "magic")
    with pytest.raises(CleaningBreakdown) as info:
        ov.clean_block(sim.block, "snooping", max_fraction=0.1)
    assert info.value.log and info.value.log[-1].action in ("breakdown", "kept", "eliminated")
