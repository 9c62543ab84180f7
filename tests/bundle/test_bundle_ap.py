"""The bundle's additional-parameter border (orientviz.bundle.problem._ap_normal) against dense algebra."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

import orientviz as ov
from orientviz.bundle import BundleOptions, ap_set
from orientviz.bundle.problem import (
    BundleProblem,
    BundleState,
    band_backward_solve,
    band_forward_solve,
    form_preconditioner,
    point_setup,
    solve_bordered,
    solve_bordered_pcg,
)
from orientviz.bundle.reduced import factor_reduced
from orientviz.camera import collinearity_jacobian


def _dense_step(prob, st, aps):
    """Gauss-Newton step from the full weighted Jacobian (images, free points, APs)."""
    block = prob.block
    m, pv, q, k = prob.m, prob.points.unknown.size, prob.q, prob.ap.k
    xyz = st.xyz[prob.obs.point]
    _, Je, Jp, _ = collinearity_jacobian(
        xyz, st.X0[prob.obs.image], st.angles[prob.obs.image], prob.interior.c[prob.obs.image], prob.interior.x0[prob.obs.image],
        prob.interior.y0[prob.obs.image], block.sequence,
    )  # fmt: skip
    n = prob.obs.image.size
    J = np.zeros((2 * n, 6 * m + 3 * pv + q))
    A = aps.design(prob.obs.xy)
    for r in range(n):
        rows = slice(2 * r, 2 * r + 2)
        J[rows, 6 * prob.obs.image[r] : 6 * prob.obs.image[r] + 6] = Je[r]
        if prob.obs.column[r] >= 0:
            c0 = 6 * m + 3 * prob.obs.column[r]
            J[rows, c0 : c0 + 3] = Jp[r]
        c0 = 6 * m + 3 * pv + k * prob.ap.group[prob.obs.image[r]]
        J[rows, c0 : c0 + k] = A[r]
    rw, _, _ = prob.residuals(st, jac=False)
    Jw = J * prob.obs.weight.reshape(-1)[:, None]
    N = Jw.T @ Jw
    b = Jw.T @ rw.reshape(-1)
    # pseudo-observations: weighted control coordinates and the parameters a = 0 ± σ
    idx = 6 * m + np.arange(3 * pv)
    N[idx, idx] += prob.points.prior_w.reshape(-1)
    b[idx] += (prob.points.prior_w * (prob.points.prior_obs - st.xyz[prob.points.unknown])).reshape(
        -1
    )
    idx = 6 * m + 3 * pv + np.arange(q)
    N[idx, idx] += prob.ap.w
    b[idx] -= prob.ap.w * st.ap
    return np.linalg.solve(N, b)


@pytest.mark.parametrize("solver", ["banded", "sparse", "dense"])
def test_step_with_group_parameters_equals_dense_solution(solver):
    sim = ov.simulate_block(3, 5, rng=21, extra=6, control_sigma=0.05)
    block = sim.block
    aps = ap_set("ebner12")
    prob = BundleProblem(
        block, point_setup(block, "weighted"), additional=aps, ap_group=block.images.strip,
        ap_sigma=10.0, options=BundleOptions(solver=solver),
    )  # fmt: skip
    assert prob.ap.G == 3 and prob.points.prior_w.any()
    rng = np.random.default_rng(3)
    st = BundleState(
        block.images.X0, block.images.angles, block.points.xyz, rng.normal(0, 3, prob.q)
    )
    rw, Je, Jp = prob.residuals(st, jac=True)
    ne = prob.normal(st, rw, Je, Jp)
    # the exact path (Fs formed; the bundle takes it when no preconditioner exists or the
    # conjugate gradients stall)
    fac = factor_reduced(prob.reduced, ne.blocks, prob.names()[: 6 * prob.m])
    dc, da, _, _ = solve_bordered(fac, ne.ap.E, ne.ap.F, ne.rhs, ne.ap.ba, prob.ap.names)
    dc, dp, da, _ = prob.back_substitute(ne, dc, da, fac)
    ref = _dense_step(prob, st, aps)
    got = np.concatenate([dc.ravel(), dp.ravel(), da])
    np.testing.assert_allclose(got, ref, rtol=1e-6, atol=1e-8 * np.abs(ref).max())


def test_band_forward_solve_equals_dense_triangular_solve():
    rng = np.random.default_rng(5)
    n, kd = 53, 7  # blocks of kd + 1 = 8 rows, the last one partial
    S = np.zeros((n, n))
    for d in range(kd + 1):
        v = rng.normal(size=n - d)
        S[np.arange(d, n), np.arange(n - d)] = v
    S = S @ S.T + n * np.eye(n)
    band = np.zeros((kd + 1, n))
    for d in range(kd + 1):
        band[d, : n - d] = np.diag(S, -d)
    L = scipy.linalg.cholesky_banded(band, lower=True)
    B = rng.normal(size=(n, 4))
    ref = scipy.linalg.solve_triangular(np.linalg.cholesky(S), B, lower=True)
    np.testing.assert_allclose(band_forward_solve(L, B), ref, rtol=1e-10, atol=1e-12)
    # single precision follows the factor's type: float32 rounding (~1e-7, cond(L) small)
    X32 = band_forward_solve(L.astype(np.float32), B)
    assert X32.dtype == np.float32
    np.testing.assert_allclose(X32, ref, rtol=1e-4, atol=1e-5 * np.abs(ref).max())


@pytest.mark.parametrize(("n", "kd"), [(53, 7), (48, 7), (5, 4)])  # last block partial,
def test_band_backward_solve_equals_dense_triangular_solve(n, kd):  # all full, one block
    rng = np.random.default_rng(7)
    S = np.zeros((n, n))
    for d in range(kd + 1):
        S[np.arange(d, n), np.arange(n - d)] = rng.normal(size=n - d)
    S = S @ S.T + n * np.eye(n)
    band = np.zeros((kd + 1, n))
    for d in range(kd + 1):
        band[d, : n - d] = np.diag(S, -d)
    L = scipy.linalg.cholesky_banded(band, lower=True)
    B = rng.normal(size=(n, 3))
    ref = scipy.linalg.solve_triangular(np.linalg.cholesky(S), B, lower=True, trans="T")
    np.testing.assert_allclose(band_backward_solve(L, B), ref, rtol=1e-10, atol=1e-12)
    # forward then backward: S⁻¹ B
    X = band_backward_solve(L, band_forward_solve(L, B))
    np.testing.assert_allclose(X, np.linalg.solve(S, B), rtol=1e-10, atol=1e-12)


def _problem(solver="banded"):
    sim = ov.simulate_block(3, 5, rng=21, extra=6, control_sigma=0.05)
    block = sim.block
    aps = ap_set("ebner12")
    prob = BundleProblem(
        block, point_setup(block, "weighted"), additional=aps, ap_group=block.images.strip,
        ap_sigma=10.0, options=BundleOptions(solver=solver),
    )  # fmt: skip
    return prob, aps


@pytest.mark.parametrize("solver", ["banded", "sparse"])
def test_conjugate_gradients_with_an_old_preconditioner_reach_the_dense_step(solver):
    prob, aps = _problem(solver)
    block = prob.block
    names = prob.names()[: 6 * prob.m]
    # preconditioner: Fs formed at a different state (start values rotated by ~0.3 gon)
    rng = np.random.default_rng(4)
    old = BundleState(
        block.images.X0 + rng.normal(0, 2, (prob.m, 3)),
        block.images.angles + rng.normal(0, 0.005, (prob.m, 3)),
        block.points.xyz, np.zeros(prob.q),
    )  # fmt: skip
    rw, Je, Jp = prob.residuals(old, jac=True)
    prob.solve(prob.normal(old, rw, Je, Jp), names)
    assert prob.run.border.preconditioner is not None and "formed" in prob.run.border.log[0]
    st = BundleState(
        block.images.X0, block.images.angles, block.points.xyz, rng.normal(0, 3, prob.q)
    )
    rw, Je, Jp = prob.residuals(st, jac=True)
    ne = prob.normal(st, rw, Je, Jp)
    fac = factor_reduced(prob.reduced, ne.blocks, names)
    dc, da, steps = solve_bordered_pcg(
        fac, ne.ap.E, ne.ap.F, ne.rhs, ne.ap.ba, prob.run.border.preconditioner, tol=1e-12
    )
    assert 1 < steps < 40
    ref = _dense_step(prob, st, aps)
    nc = 6 * prob.m
    np.testing.assert_allclose(dc, ref[:nc], rtol=1e-6, atol=1e-8 * np.abs(ref).max())
    np.testing.assert_allclose(da, ref[-prob.q :], rtol=1e-6, atol=1e-8 * np.abs(ref).max())
    # the bundle's own step (default tolerance) takes the iterative path
    prob.solve(ne, names)
    assert prob.run.border.log[-1].startswith("cg")
    # the single-precision preconditioner of this very system: CG converges in very few
    # steps to the same step
    if solver == "banded":
        prec = form_preconditioner(fac, ne.ap.E, ne.ap.F)
        dc2, da2, steps2 = solve_bordered_pcg(
            fac, ne.ap.E, ne.ap.F, ne.rhs, ne.ap.ba, prec, tol=1e-12
        )
        assert steps2 <= steps
        np.testing.assert_allclose(da2, ref[-prob.q :], rtol=1e-6, atol=1e-8 * np.abs(ref).max())


def test_border_blocks_apply_like_the_dense_border():
    prob, _ = _problem()
    block = prob.block
    st = BundleState(block.images.X0, block.images.angles, block.points.xyz, np.zeros(prob.q))
    rw, Je, Jp = prob.residuals(st, jac=True)
    ne = prob.normal(st, rw, Je, Jp)
    Eb = ne.ap.E_border
    E = ne.ap.E  # formed on demand from the blocks
    assert E.shape == (6 * prob.m, prob.q)
    assert Eb.other.shape[0] > 0  # points in two strips: blocks outside the own group
    rng = np.random.default_rng(2)
    v, y = rng.normal(size=prob.q), rng.normal(size=6 * prob.m)
    np.testing.assert_allclose(Eb @ v, E @ v, rtol=1e-12, atol=1e-12 * np.abs(E @ v).max())
    np.testing.assert_allclose(Eb.T @ y, E.T @ y, rtol=1e-12, atol=1e-12 * np.abs(E.T @ y).max())
