"""Free networks: null space, inner constraints, S-transformation, estimable quantities."""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.adjust.datum import datum_solve, helmert_basis, s_transformation
from orientviz.adjust.network2d import all_pairs_within, distance_equations
from orientviz.errors import InputError


def _network(seed=9):
    rng = np.random.default_rng(seed)
    xy = np.array([[0, 0], [400, 30], [820, -20], [60, 420], [450, 380], [880, 430], [300, 760.0]])
    pairs = all_pairs_within(xy, 600)
    model = distance_equations(pairs)
    l = model(xy.reshape(-1))[0] + rng.normal(0, 0.003, len(pairs))
    x0 = xy.reshape(-1) + rng.normal(0, 0.05, xy.size)
    f, J = model(x0)
    N, b = J.T @ J / 0.003**2, J.T @ (l - f) / 0.003**2
    return x0, pairs, J, N, b, helmert_basis(x0.reshape(-1, 2))


def test_the_basis_spans_the_null_space_of_distances_2d_and_3d():
    x0, pairs, J, N, b, G = _network()
    assert G.shape == (14, 3)
    assert np.abs(J @ G).max() < 1e-12
    assert np.linalg.matrix_rank(N, tol=1e-8 * np.abs(N).max()) == 14 - 3
    # 3-D: an infinitesimal rigid motion w × (X − X̄) + t is a combination of the six columns
    rng = np.random.default_rng(1)
    X = rng.normal(size=(5, 3)) * 100
    G3 = helmert_basis(X)
    d = (np.cross([1e-6, -2e-6, 3e-6], X - X.mean(0)) + [1e-4, 2e-4, -1e-4]).reshape(-1)
    coef, *_ = np.linalg.lstsq(G3, d, rcond=None)
    assert np.linalg.norm(G3 @ coef - d) < 1e-9 * np.linalg.norm(d)
    assert helmert_basis(X, scale=True).shape == (15, 7)


def test_inner_constraints_give_the_pseudo_inverse():
    x0, pairs, J, N, b, G = _network()
    dx, Q = datum_solve(N, b, G)
    np.testing.assert_allclose(Q, np.linalg.pinv(N), atol=1e-12 * np.abs(Q).max() * 1e3)
    assert np.abs(G.T @ dx).max() < 1e-12
    # minimum trace among datums
    _, QB = datum_solve(N, b, G, datum_points=[0, 1])
    assert np.trace(Q) < np.trace(QB)


def test_s_transformation_equals_a_new_adjustment_and_keeps_distances():
    x0, pairs, J, N, b, G = _network()
    dxA, QA = datum_solve(N, b, G)
    dxB, QB = datum_solve(N, b, G, datum_points=[2, 5, 6])
    S = s_transformation(G, datum_points=[2, 5, 6])
    np.testing.assert_allclose(S @ dxA, dxB, atol=1e-12)
    np.testing.assert_allclose(S @ QA @ S.T, QB, atol=1e-12 * np.abs(QB).max() * 1e3)
    # the adjusted distances and their precision do not depend on the datum
    np.testing.assert_allclose(J @ dxA, J @ dxB, atol=1e-12)
    np.testing.assert_allclose(J @ QA @ J.T, J @ QB @ J.T, rtol=1e-8, atol=1e-20)


def test_too_few_datum_points_are_rejected():
    x0, pairs, J, N, b, G = _network()
    with pytest.raises(InputError, match="datum"):
        datum_solve(N, b, G, datum_points=[3])
    with pytest.raises(InputError, match="datum"):
        s_transformation(G, datum_points=[3])
    with pytest.raises(InputError):
        distance_equations([[0, 0]])
