"""The points of a robust run: each point's Newton correction and its search
(:mod:`orientviz.bundle.loop._tail`), on DBAT's sxb block with planted gross errors."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from orientviz.bundle.loop import _steps, _tail
from orientviz.bundle.loop._loss import RobustLoss
from orientviz.io.kinds.block import adjust_block
from planted_outliers import planted_dbat


def _solve(prob, block, loss, **options):
    p = copy.deepcopy(prob)
    p.options.update(robust=loss, **options)
    adj, _ = adjust_block(p, copy.deepcopy(block), precision=False)
    return adj


@pytest.fixture(scope="module")
def planted():
    return planted_dbat("dbat_sxb")


@pytest.fixture(scope="module")
def calls(planted):
    """The arguments of the first point search of a Huber run (and of its Newton step)."""
    seen = {}
    newton, search = _steps.point_newton, _steps.point_search

    def keep_newton(*a, **k):
        out = newton(*a, **k)
        seen.setdefault("newton", (a, out))
        return out

    def keep_search(*a, **k):
        out = search(*a, **k)
        seen.setdefault("search", (a, out))
        return out

    mp = pytest.MonkeyPatch()
    mp.setattr(_steps, "point_newton", keep_newton)
    mp.setattr(_steps, "point_search", keep_search)
    try:
        _solve(*planted, "huber")
    finally:
        mp.undo()
    return seen


@pytest.mark.parametrize("kind", ["huber", "soft_l1", "cauchy"])
def test_curvature_ratio_along_the_misclosure(kind):
    """(ρ′ + 2sρ″)/ρ′ against central differences of ρ′ (Cauchy clipped at 0)."""
    loss = RobustLoss.named(kind, 1.5)
    s = np.array([0.3, 1.0, 2.0, 5.0, 40.0, 900.0])
    h = 1e-6 * s
    d1 = (loss(s + h)[1] - loss(s - h)[1]) / (2 * h)
    want = np.maximum((loss(s)[1] + 2 * s * d1) / loss(s)[1], 0.0)
    assert np.allclose(loss.along(s), want, atol=1e-6)


def test_newton_correction_minimises_each_points_true_model(calls):
    """Each active point's Newton correction minimises the model of its rays' Σρ,
    rewritten here: misclosures after the images' correction, linearised, r − J δ; the
    curvature ρ′ + 2sρ″ along r (ρ″ by differences) and ρ′ across, plus the floor times
    the reweighted model, the prior and λ times the reweighted block's diagonal."""
    (prob, loss, bw, st, lin, dc, da, lam), pn = calls["newton"]
    assert pn is not None and pn.active.size > 10
    rw, Je, Jp, scale = lin
    obs, pts = prob.obs, prob.points
    checked = 0
    for i in np.linspace(0, pn.active.size - 1, 12).astype(int):
        j = pn.active[i]
        rays = np.flatnonzero(obs.column == j)
        w = bw[rays]
        J = Jp[rays] * w[:, :, None]
        u = np.einsum("nij,nj->ni", Je[rays], dc[obs.image[rays]]) * w
        r = rw[rays] / scale[rays, None] - u
        s = np.sum(r * r, axis=1)
        rho1 = loss(s)[1]
        h = 1e-7 * np.maximum(s, 1.0)
        rho2 = (loss(s + h)[1] - loss(s - h)[1]) / (2 * h)
        H, M, g = np.zeros((3, 3)), np.zeros((3, 3)), np.zeros(3)
        for n in range(rays.size):
            M += rho1[n] * J[n].T @ J[n]
            H += J[n].T @ (rho1[n] * np.eye(2) + 2 * rho2[n] * np.outer(r[n], r[n])) @ J[n]
            g += rho1[n] * J[n].T @ r[n]
        M += np.diag(pts.prior_w[j])
        H += np.diag(pts.prior_w[j]) + _tail.NEWTON_FLOOR * M + lam * np.diag(np.diag(M))
        g += pts.prior_w[j] * (pts.prior_obs[j] - st.xyz[pts.unknown[j]])
        if np.linalg.cond(H) > 1e8:
            continue
        want = np.linalg.solve(H, g)
        assert np.allclose(pn.dp[i], want, rtol=1e-5, atol=1e-7 * np.abs(want).max())
        checked += 1
    assert checked >= 6


def test_first_breakpoint_is_where_a_ray_reaches_the_scale(calls):
    """Along each active point's Newton correction (misclosures linearised) no ray beyond
    the scale reaches it before the fraction ``first``, and where ``first`` < 1 one does
    there."""
    (prob, loss, bw, st, lin, dc, da, lam), pn = calls["newton"]
    rw, Je, Jp, scale = lin
    obs, b = prob.obs, loss.scale**2
    inside = 0
    for i in range(pn.active.size):
        rays = np.flatnonzero(obs.column == pn.active[i])
        w = bw[rays]
        u = np.einsum("nij,nj->ni", Je[rays], dc[obs.image[rays]]) * w
        r = rw[rays] / scale[rays, None] - u
        up = np.einsum("nij,j->ni", Jp[rays] * w[:, :, None], pn.dp[i])
        out = np.sum(r * r, axis=1) > b

        f = pn.first[i]
        before, at = (np.sum((r - x * up) ** 2, axis=1)[out] for x in (0.999 * f, f))
        assert np.all(before > b * (1 - 1e-9))
        if f < 1:
            assert np.min(np.abs(at - b)) < 1e-6 * b
            inside += 1
    assert inside > 5


def test_search_keeps_no_point_worse_than_the_joint_step(calls):
    """Given the images' new parameters each point's rays (and prior) have a Σρ at most
    that of the joint step's own correction, some points move otherwise, and the search
    reports what they saved."""
    (prob, loss, bw, st, dc, da, dp, pn, *_), (out, moved, gain) = calls["search"]
    assert moved > 0

    def per_point(d):
        prob.obs.weight[...] = bw
        rw = prob.residuals(prob.apply(st, dc, d, da), jac=False)[0]
        rho = loss(np.sum(rw * rw, axis=1))[0]
        col = prob.obs.column
        c = np.bincount(col[col >= 0], weights=rho[col >= 0], minlength=prob.points.unknown.size)
        v = prob.points.prior_obs - st.xyz[prob.points.unknown] - d
        return c + np.sum(prob.points.prior_w * v * v, axis=1)

    before, after = per_point(dp), per_point(out)
    assert np.all(after <= before + 1e-9 * np.abs(before))
    assert np.sum(after < before) == moved
    assert gain == pytest.approx(np.sum(before - after), rel=1e-9)


@pytest.mark.parametrize("loss", ["huber", "soft_l1"])
def test_point_search_shortens_the_run_to_the_same_optimum(planted, loss, monkeypatch):
    """With the search the run takes at most 60 % of the steps without it and stops at its
    optimum: ½Σρ within 1e-6 (relative) of a run without it to corrections below 1e-4 σ."""
    fast = _solve(*planted, loss)
    monkeypatch.setattr(_steps.BundleSteps, "_point_newton", lambda self, *a: None)
    slow = _solve(*planted, loss)
    tight = _solve(*planted, loss, ftol=1e-15, tol=1e-4, max_iter=60)
    assert fast.converged and slow.converged and tight.converged
    n_fast, n_slow = len(fast.history) - 1, len(slow.history) - 1
    assert n_fast <= 0.6 * n_slow
    best = tight.history[-1].cost
    assert abs(fast.history[-1].cost - best) <= 1e-6 * best
