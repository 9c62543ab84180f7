"""Block structure of the bundle's normal equations against dense computations."""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.bundle.sparsity import (
    bandwidth,
    block_pattern,
    bundle_normal_blocks,
    cholesky_fill,
    reduced_pattern,
)


@pytest.fixture(scope="module")
def small():
    sim = ov.simulate_block(2, 5, rng=3, extra=None)
    return sim, bundle_normal_blocks(sim.block)


def test_one_dense_step_equals_the_bundles_first_iteration(small):
    sim, nb = small
    N, b = nb.dense()
    d = np.linalg.solve(N, b)
    m = nb.n_images
    res = ov.bundle_adjust(sim.block, max_iter=1, precision=False)
    got = res.x[res.groups["exterior"]].reshape(-1, 6)
    np.testing.assert_allclose(
        got[:, :3], sim.block.images.X0 + d[: 6 * m].reshape(-1, 6)[:, :3], atol=1e-6
    )


def test_patterns_match_the_non_zeros(small):
    sim, nb = small
    N, _ = nb.dense()
    m, q = nb.n_images, nb.n_points
    P = block_pattern(nb.obs_image, nb.obs_unknown, m, q)
    edges = np.concatenate([[0], np.cumsum(np.where(np.arange(m + q) < m, 6, 3))])
    nz = np.array([[np.any(N[edges[r]:edges[r + 1], edges[c]:edges[c + 1]] != 0) for c in range(m + q)]
                   for r in range(m + q)])  # fmt: skip
    np.testing.assert_array_equal(P, nz)
    Vi = np.linalg.inv(N[6 * m :, 6 * m :])
    S = N[: 6 * m, : 6 * m] - N[: 6 * m, 6 * m :] @ Vi @ N[6 * m :, : 6 * m]
    Snz = np.array([[np.abs(S[6 * r:6 * r + 6, 6 * c:6 * c + 6]).max() > 1e-9 * np.abs(S).max()
                     for c in range(m)] for r in range(m)])  # fmt: skip
    np.testing.assert_array_equal(reduced_pattern(nb.obs_image, nb.obs_unknown, m), Snz)


def test_symbolic_fill_equals_a_numerical_factor_and_bandwidth_counts_offsets():
    rng = np.random.default_rng(2)
    for _ in range(5):
        A = rng.random((15, 15)) < 0.15
        P = A | A.T | np.eye(15, dtype=bool)
        M = np.where(P, rng.uniform(0.1, 1.0, P.shape), 0.0)
        M = M + M.T + 50 * np.eye(15)
        L = np.abs(np.linalg.cholesky(M)) > 1e-13
        np.testing.assert_array_equal(cholesky_fill(P), L)
        b = max(abs(i - k) for i in range(15) for k in range(15) if P[i, k])
        assert bandwidth(P) == b
        o = rng.permutation(15)
        assert bandwidth(P, o) == max(
            abs(i - k) for i in range(15) for k in range(15) if P[o[i], o[k]]
        )
