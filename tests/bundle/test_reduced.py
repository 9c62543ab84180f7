"""Schur complement and reduced-system solvers (orientviz.bundle.reduced)."""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.bundle import BundleOptions
from orientviz.bundle.problem import BundleProblem, BundleState, point_setup
from orientviz.bundle.reduced import SOLVERS, geometric_orderings, inv3
from orientviz.camera import collinearity_jacobian


def _problem(solver="banded", strips=2, n=4, control="fixed", seed=3):
    sim = ov.simulate_block(strips, n, rng=seed, extra=8, control="perimeter")
    block = sim.block
    setup = point_setup(block, control)
    prob = BundleProblem(block, setup, options=BundleOptions(solver=solver))
    st = BundleState(
        block.images.X0.copy(), block.images.angles.copy(), block.points.xyz.copy(), np.zeros(0)
    )
    return block, prob, st


def _dense_full_solution(block, prob, st):
    """Gauss-Newton step from the full (not reduced) normal equations, built densely."""
    obs = block.observations
    u = prob.obs.index
    cam = block.images.camera[obs.image[u]]
    xy, Je, Jp, _ = collinearity_jacobian(
        st.xyz[obs.point[u]],
        st.X0[obs.image[u]],
        st.angles[obs.image[u]],
        block.cameras.c[cam],
        block.cameras.x0[cam],
        block.cameras.y0[cam],
        block.sequence,
    )
    n, m, pv = u.size, block.n_images, prob.points.unknown.size
    J = np.zeros((2 * n, 6 * m + 3 * pv))
    for i in range(n):
        ci = obs.image[u[i]]
        J[2 * i : 2 * i + 2, 6 * ci : 6 * ci + 6] = Je[i]
        col = prob.points.column[obs.point[u[i]]]
        if col >= 0:
            J[2 * i : 2 * i + 2, 6 * m + 3 * col : 6 * m + 3 * col + 3] = Jp[i]
    w = (1.0 / obs.sigma[u] ** 2).reshape(-1)
    r = (obs.xy[u] - xy).reshape(-1)
    N = J.T @ (w[:, None] * J)
    b = J.T @ (w * r)
    # control pseudo-observations of unknown points (weighted control)
    pw = prob.points.prior_w.reshape(-1)
    idx = 6 * m + np.arange(3 * pv)
    N[idx, idx] += pw
    b[idx] += pw * (prob.points.prior_obs - st.xyz[prob.points.unknown]).reshape(-1)
    return np.linalg.solve(N, b)


@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("control", ["fixed", "weighted"])
def test_schur_equals_dense_full_normal_equations(solver, control):
    block, prob, st = _problem(solver, control=control)
    if control == "weighted":
        block.points.sigma[block.points.role == 1] = 0.05
        prob = BundleProblem(
            block, point_setup(block, control), options=BundleOptions(solver=solver)
        )
    rw, Je, Jp = prob.residuals(st, jac=True)
    dc, dp, da, _ = prob.solve(prob.normal(st, rw, Je, Jp), prob.names()[: 6 * prob.m])
    ref = _dense_full_solution(block, prob, st)
    got = np.concatenate([dc.ravel(), dp.ravel()])
    # same linear system solved two ways: agreement to rounding of a well-posed system
    np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-9 * np.abs(ref).max())


def test_inv3_matches_numpy():
    rng = np.random.default_rng(0)
    A = rng.normal(size=(50, 3, 3))
    A = A @ A.transpose(0, 2, 1) + 0.1 * np.eye(3)
    np.testing.assert_allclose(inv3(A), np.linalg.inv(A), rtol=1e-10, atol=1e-12)


def test_geometric_ordering_numbers_across_strips():
    # 3 strips of 10 images: the narrow numbering goes across the strips (columns of 3)
    X, Y = np.meshgrid(np.arange(10) * 920.0, np.arange(3) * 1840.0)
    X0 = np.column_stack([X.ravel(), Y.ravel(), np.full(30, 1500.0)])
    orders = geometric_orderings(X0)
    cols = [np.round(X0[o[:3], 0]).tolist() for o in orders]
    assert [0.0, 0.0, 0.0] in cols  # one candidate starts with the first column


def test_banded_ordering_beats_or_equals_rcm():
    _, prob, _ = _problem("banded", strips=3, n=8)
    info = prob.reduced.info
    assert info["bandwidth_images"] <= info["bandwidth_rcm"]


def test_singular_reduced_system_names_parameters():
    block, prob, st = _problem("banded")
    rw, Je, Jp = prob.residuals(st, jac=True)
    ne = prob.normal(st, rw, Je, Jp)
    # remove everything that determines image 0's κ: a zero row/column in S
    ne.blocks[:, 5, :] = 0.0
    ne.blocks[:, :, 5] = 0.0
    with pytest.raises(ov.NotDeterminableError) as info:
        prob.solve(ne, prob.names()[: 6 * prob.m])
    assert any(p.endswith(".kappa") for p in info.value.parameters)


def test_schur_maps_of_ascending_tracks_equal_the_general_ones():
    # the bundle's set-up orders a point's rays by image: the maps of S's formation are
    # then built from one point's pattern; they must be the general construction's
    from orientviz.bundle.reduced._tracks import _ascending_group_map, _block_lookup, _group_map

    rng = np.random.default_rng(2)
    m = 40
    for k in (2, 3, 5):
        img = np.sort(
            np.stack([rng.choice(m, k, replace=False) for _ in range(25)]), axis=1
        ).astype(np.int64)
        i, j = np.triu_indices(k)
        keys = np.union1d(img[:, i] * m + img[:, j], np.arange(m) * (m + 1))
        lookup = _block_lookup(keys, m)
        fast = _ascending_group_map(img, lookup, keys.size)
        ref = _group_map(img, lookup, keys.size)
        assert fast.shape == ref.shape
        assert np.array_equal(fast.indptr, ref.indptr)
        assert np.array_equal(fast.indices, ref.indices)
        assert np.array_equal(fast.data, ref.data)
