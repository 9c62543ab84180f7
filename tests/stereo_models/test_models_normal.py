"""Sparse model normal equations: LinearSolution.resolve against dense least squares."""

import numpy as np
import pytest
import scipy.sparse as sp

from orientviz.stereo_models import solve_rows, solve_sparse


def _mixed_system(seed: int = 3):
    """Rows with sign −1 (model rows), +1 (direct observations of a coordinate), 0 and
    no scalar at all, reduced unknowns coupled across rows, diverse weights."""
    rng = np.random.default_rng(seed)
    n, na, ns = 90, 7, 15
    Ja = rng.normal(size=(n, na)) * (rng.uniform(size=(n, na)) < 0.5)
    row_scalar = rng.integers(-1, ns, n)
    row_scalar[:ns] = np.arange(ns)  # every scalar unknown has a model row …
    sign = np.where(rng.uniform(size=n) < 0.3, 1.0, -1.0)
    sign[:ns] = -1.0
    sign[ns : ns + 10] = 1.0  # … and several direct observations
    sign[ns + 10 : ns + 13] = 0.0  # a zero coefficient: the row has no scalar
    w = rng.uniform(0.3, 3.0, n)
    prior_w = np.where(rng.uniform(size=ns) < 0.4, rng.uniform(0.5, 2.0, ns), 0.0)
    return Ja, row_scalar, sign, w, prior_w, ns


def _dense(Ja, row_scalar, sign, w, r, ns, prior_w, prior_e):
    """Gauss-Markov normal equations of v = r + Ja·da + sign·dX, plus dX + e pseudo-rows."""
    n, na = Ja.shape
    A = np.zeros((n, na + ns))
    A[:, :na] = Ja
    has = row_scalar >= 0
    A[np.flatnonzero(has), na + row_scalar[has]] = sign[has]
    N = (A.T * w) @ A
    b = -(A.T * w) @ r
    N[na:, na:] += np.diag(prior_w)
    b[na:] -= prior_w * prior_e
    x = np.linalg.solve(N, b)
    return x[:na], x[na:]


def test_resolve_with_direct_coordinate_observations_equals_a_fresh_solve():
    Ja, row_scalar, sign, w, prior_w, ns = _mixed_system()
    rng = np.random.default_rng(11)
    r0 = rng.normal(size=w.size)
    sol = solve_sparse(sp.csr_matrix(Ja), row_scalar, sign, w, r0, ns, prior_w=prior_w,
                       prior_e=np.zeros(ns))  # fmt: skip
    # the first solve itself agrees with the dense normal equations
    da, dX = _dense(Ja, row_scalar, sign, w, r0, ns, prior_w, np.zeros(ns))
    np.testing.assert_allclose(sol.dtheta, da, rtol=1e-9, atol=1e-11)
    np.testing.assert_allclose(sol.dX, dX, rtol=1e-9, atol=1e-11)
    for _ in range(3):  # new misclosures, same factorisation
        r = rng.normal(size=w.size)
        e = rng.normal(size=ns)
        da, dX = _dense(Ja, row_scalar, sign, w, r, ns, prior_w, e)
        got_a, got_X = sol.resolve(r, prior_e=e)
        np.testing.assert_allclose(got_a, da, rtol=1e-9, atol=1e-11)
        np.testing.assert_allclose(got_X, dX, rtol=1e-9, atol=1e-11)
        # without prior misclosures: the pseudo-observations read dX = 0
        da0, dX0 = _dense(Ja, row_scalar, sign, w, r, ns, prior_w, np.zeros(ns))
        got_a, got_X = sol.resolve(r)
        np.testing.assert_allclose(got_a, da0, rtol=1e-9, atol=1e-11)
        np.testing.assert_allclose(got_X, dX0, rtol=1e-9, atol=1e-11)


def test_resolve_of_model_rows_keeps_the_model_shape():
    rng = np.random.default_rng(4)
    n_models, p, ns, n = 4, 3, 10, 60
    row_model = rng.integers(0, n_models, n)
    row_scalar = rng.integers(-1, ns, n)
    row_scalar[:ns] = np.arange(ns)
    J = rng.normal(size=(n, p))
    w = rng.uniform(0.5, 2.0, n)
    r = rng.normal(size=n)
    sol = solve_rows(row_model, J, row_scalar, w, np.zeros(n), n_models, ns)
    fresh = solve_rows(row_model, J, row_scalar, w, r, n_models, ns)
    dt, dX = sol.resolve(r)
    assert dt.shape == (n_models, p)
    np.testing.assert_allclose(dt, fresh.dtheta, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(dX, fresh.dX, rtol=1e-9, atol=1e-12)


def test_resolve_refuses_wrong_length():
    Ja, row_scalar, sign, w, prior_w, ns = _mixed_system()
    sol = solve_sparse(sp.csr_matrix(Ja), row_scalar, sign, w, np.zeros(w.size), ns)
    with pytest.raises(ValueError, match="misclosures"):
        sol.resolve(np.zeros(w.size - 1))
