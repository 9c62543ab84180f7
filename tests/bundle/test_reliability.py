"""Reliability of the rays of a bundle block against brute force: inject, re-adjust, compare.

The reference is the bundle itself: error-free observations (the simulation's truth) plus
a bias on one ray, adjusted again from the true values. The residuals then are the bias's
effect alone, so the 2-D test statistic of the ray is its non-centrality, and the change
of the estimates is its external effect. The bias is scaled to 1e-4 of the MDB, where the
collinearity equations are linear to ~1e-8 (the predictions are first-order); at the full
MDB the same comparison holds to the size of the second-order terms (~1e-3).
"""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.adjust.gross import noncentrality
from orientviz.adjust.gross2d import noncentrality_2d, statistic_2d
from orientviz.block import TIE
from orientviz.bundle import ray_reliability

EPS = 1e-4  # bias = EPS × MDB: first-order regime
TOL = 1e-10  # bundle stopping rule (fraction of the conditional σ)


class Affinity:
    """Affinity and shear as additional parameters (µm at x = 100 mm)."""

    name = "affinity"
    names = ["a1", "a2"]

    def design(self, xy):
        A = np.zeros((xy.shape[0], 2, 2))
        A[:, 0, 0] = 1e-3 * xy[:, 0] / 100.0
        A[:, 1, 0] = -1e-3 * xy[:, 1] / 100.0
        A[:, 1, 1] = 1e-3 * xy[:, 0] / 100.0
        return A


def _case(case):
    sim = ov.simulate_block(2, 4, rng=11, extra=6, n_check=2)
    block = sim.truth.copy()
    kw = {"tol": TOL}
    if case == "weighted":
        block.points.sigma[block.points.role == 1] = 0.03
        kw["control"] = "weighted"
    if case == "ap":
        kw.update(additional=Affinity(), ap_group=np.arange(block.n_images) % 2, ap_sigma=50.0)
    return block, kw


def _adjust_with_bias(block, kw, j, bias):
    b = block.copy()
    b.observations.xy[j] += bias
    return ov.bundle_adjust(b, **kw)


def _shifts(a0, a1, block, j):
    p0, p1 = a0["points"].reshape(-1, 3), a1["points"].reshape(-1, 3)
    e0, e1 = a0["exterior"].reshape(-1, 6), a1["exterior"].reshape(-1, 6)
    return p1[block.observations.point[j]] - p0[block.observations.point[j]], (
        e1[block.observations.image[j]] - e0[block.observations.image[j]]
    )


@pytest.fixture(scope="module", params=["fixed", "weighted", "ap"])
def setup(request):
    block, kw = _case(request.param)
    adj = ov.bundle_adjust(block, **kw)
    rel = ray_reliability(adj, block)
    k = block.rays_per_point()[rel.point]
    tie3 = np.flatnonzero(rel.testable & (block.points.role[rel.point] == TIE) & (k == 3))
    return block, kw, adj, rel, tie3[0]


def test_weak_direction_mdb_has_noncentrality_delta0_squared(setup):
    block, kw, adj, rel, j = setup
    n = block.n_observations
    a1 = _adjust_with_bias(block, kw, j, EPS * rel.bias_weak[j])
    z = (a1.residuals[: 2 * n] / a1.sigma_obs[: 2 * n]).reshape(n, 2)
    r = adj.redundancy_numbers[: 2 * n].reshape(n, 2)
    T, dof = statistic_2d(z[[j]], r[[j]], adj.redundancy_xy[[j]])
    assert dof[0] == 2
    np.testing.assert_allclose(T[0] / EPS**2, rel.delta0**2, rtol=1e-6)
    # the formula of gross2d gives the same, and the MDB follows δ0 σ / √r_min
    sig = block.observations.sigma[[j]]
    lam = noncentrality_2d(rel.bias_weak[[j]], sig, r[[j]], adj.redundancy_xy[[j]])
    np.testing.assert_allclose(lam[0], noncentrality() ** 2, rtol=1e-10)
    np.testing.assert_allclose(rel.mdb_weak[j], rel.delta0 * sig[0, 0] / np.sqrt(rel.r_min[j]))
    assert rel.mdb_strong[j] < rel.mdb_weak[j]


def test_external_effects_equal_the_readjustment(setup):
    block, kw, adj, rel, j = setup
    a1 = _adjust_with_bias(block, kw, j, EPS * rel.bias_weak[j])
    dp, de = _shifts(adj, a1, block, j)
    assert np.linalg.norm(rel.point_shift[j]) > 0.05  # m: a visible effect, not a null test
    np.testing.assert_allclose(
        dp / EPS, rel.point_shift[j], rtol=0, atol=1e-6 * np.linalg.norm(dp / EPS)
    )
    for sl in (slice(0, 3), slice(3, 6)):  # positions (m) and angles (rad) separately
        ref = de[sl] / EPS
        np.testing.assert_allclose(
            ref, rel.exterior_shift[j, sl], rtol=0, atol=1e-6 * np.linalg.norm(ref)
        )
    # δ̄0: the bias changes the adjusted observations by Δl̂ with ‖P½ Δl̂‖ = δ̄0 (all rows,
    # pseudo-observations included); Δl̂ = ∇ + Δv for the ray, Δv for the others
    dv = (a1.residuals - adj.residuals) / adj.sigma_obs
    dv[2 * j : 2 * j + 2] += EPS * rel.bias_weak[j] / block.observations.sigma[j]
    dv = dv[np.isfinite(adj.redundancy_numbers)]  # rays of check points are not adjusted
    np.testing.assert_allclose(np.linalg.norm(dv) / EPS, rel.external[j], rtol=1e-6)


def test_largest_shift_on_the_mdb_ellipse(setup):
    """Gains measured from two re-adjustments, then the maximum over 7200 directions."""
    block, kw, adj, rel, j = setup
    n = block.n_observations
    sig = block.observations.sigma[j]
    u = rel.weak_direction[j]
    E = np.column_stack([u, [-u[1], u[0]]])  # σ-normalised biases, columns
    Kp, Kc = np.zeros((3, 2)), np.zeros((3, 2))
    for k in range(2):
        a1 = _adjust_with_bias(block, kw, j, EPS * E[:, k] * sig)
        dp, de = _shifts(adj, a1, block, j)
        Kp[:, k], Kc[:, k] = dp / EPS, de[:3] / EPS
    Kp, Kc = Kp @ E.T, Kc @ E.T  # responses to the unit biases of x and y (E orthonormal)
    # biases e(θ) with eᵀ R e = δ0², R from the adjustment
    r = adj.redundancy_numbers[: 2 * n].reshape(n, 2)[j]
    R = np.array([[r[0], adj.redundancy_xy[j]], [adj.redundancy_xy[j], r[1]]])
    t = np.linspace(0.0, np.pi, 7200, endpoint=False)
    d = np.stack([np.cos(t), np.sin(t)])
    d = d * rel.delta0 / np.sqrt(np.einsum("it,ij,jt->t", d, R, d))
    got_p = np.linalg.norm(Kp @ d, axis=0).max()
    got_c = np.linalg.norm(Kc @ d, axis=0).max()
    # a dense sampling undershoots the maximum by at most ~(π/7200)²/2 relative
    assert rel.point_shift_max[j] == pytest.approx(got_p, rel=2e-6)
    assert rel.centre_shift_max[j] == pytest.approx(got_c, rel=2e-6)
    assert rel.point_shift_max[j] >= np.linalg.norm(rel.point_shift[j]) * (1 - 1e-12)


def test_full_size_mdb_is_found_at_delta0_to_second_order():
    block, kw = _case("fixed")
    adj = ov.bundle_adjust(block, **kw)
    rel = ray_reliability(adj, block)
    n = block.n_observations
    j = np.flatnonzero(rel.testable & (block.points.role[rel.point] == TIE))[0]
    a1 = _adjust_with_bias(block, kw, j, rel.bias_weak[j])
    z = (a1.residuals[: 2 * n] / a1.sigma_obs[: 2 * n]).reshape(n, 2)
    r = adj.redundancy_numbers[: 2 * n].reshape(n, 2)
    T, _ = statistic_2d(z[[j]], r[[j]], adj.redundancy_xy[[j]])
    assert T[0] == pytest.approx(rel.delta0**2, rel=2e-3)
    dp, _ = _shifts(adj, a1, block, j)
    np.testing.assert_allclose(dp, rel.point_shift[j], atol=2e-3 * np.linalg.norm(dp))


def test_two_ray_points_are_blind_along_the_base():
    block, kw = _case("fixed")
    adj = ov.bundle_adjust(block, **kw)
    rel = ray_reliability(adj, block)
    n = block.n_observations
    k = block.rays_per_point()[rel.point]
    two = rel.used & (k == 2) & (block.points.role[rel.point] == TIE)
    assert two.any() and (rel.used & (k >= 3) & rel.testable).any()
    assert not rel.testable[two].any()
    assert np.isinf(rel.mdb_weak[two]).all() and np.isinf(rel.point_shift_max[two]).all()
    assert np.isfinite(rel.mdb_strong[two]).all()  # the y-parallax is still tested
    # the weak direction is the base (in the image: x within a strip, y across strips)
    o = block.observations
    for j in np.flatnonzero(two):
        i, other = o.image[j], o.image[(o.point == o.point[j]) & (o.image != o.image[j])][0]
        R = ov.matrix_from_opk(*block.images.angles[i], sequence=block.sequence)
        base = (R.T @ (block.images.X0[other] - block.images.X0[i]))[:2]
        assert abs(rel.weak_direction[j] @ base) / np.linalg.norm(base) > 0.99
    # brute force: 30 µm along it leaves every residual as it was, yet moves the point
    j = np.flatnonzero(two)[0]
    a1 = _adjust_with_bias(block, kw, j, 0.030 * rel.weak_direction[j])
    z = (a1.residuals[: 2 * n] / a1.sigma_obs[: 2 * n]).reshape(n, 2)
    assert np.abs(z).max() < 1e-3  # in σ: nothing to test
    dp, _ = _shifts(adj, a1, block, j)
    assert np.linalg.norm(dp) > 0.1  # m


def test_unused_rays_fixed_points_and_per_point_summary():
    sim = ov.simulate_block(3, 6, rng=4, n_check=6)
    adj = ov.bundle_adjust(sim.block)
    rel = ray_reliability(adj, sim.block)
    o = sim.block.observations
    chk = sim.block.points.role[o.point] == 2
    assert chk.any() and not rel.used[chk].any()
    assert np.isnan(rel.mdb_weak[chk]).all() and np.isnan(rel.point_shift_max[chk]).all()
    ctrl = rel.testable & (sim.block.points.role[o.point] == 1)
    assert ctrl.any()
    assert np.all(rel.point_shift[ctrl] == 0.0)  # fixed control does not move
    worst = rel.by_point(rel.mdb_weak, sim.block.n_points)
    for p in np.unique(o.point[rel.used])[:20]:
        assert worst[p] == np.max(rel.mdb_weak[(o.point == p) & rel.used])
    assert np.isnan(worst[np.unique(o.point[chk])]).all()
    with pytest.raises(ov.InputError):
        rel.by_point(rel.mdb_weak, sim.block.n_points, reduce="mean")


def test_bad_input():
    sim = ov.simulate_block(2, 4, rng=11)
    with pytest.raises(ov.InputError, match="precision=True"):
        ray_reliability(ov.bundle_adjust(sim.block, precision=False), sim.block)
    other = ov.simulate_block(2, 5, rng=11)
    with pytest.raises(ov.InputError, match="rays"):
        ray_reliability(ov.bundle_adjust(sim.block), other.block)
