"""Theoretical block precision (orientviz.simulate) and its Schur-complement cofactors."""

import numpy as np
import pytest

from orientviz.simulate import fit_log_law, height_precision, planimetric_precision
from orientviz.stereo_models import scalar_cofactors, solve_rows


def test_schur_cofactors_equal_the_dense_inverse():
    rng = np.random.default_rng(0)
    n_models, p, n_scalar, n = 5, 3, 12, 80
    row_model = rng.integers(0, n_models, n)
    row_scalar = rng.integers(-1, n_scalar, n)
    row_scalar[:n_scalar] = np.arange(n_scalar)  # every unknown observed
    J = rng.normal(size=(n, p))
    w = rng.uniform(0.5, 2.0, n)
    sol = solve_rows(row_model, J, row_scalar, w, np.zeros(n), n_models, n_scalar)
    # the full design [J_model, −I_scalar] and its normal matrix
    A = np.zeros((n, n_models * p + n_scalar))
    for i in range(n):
        A[i, row_model[i] * p : row_model[i] * p + p] = J[i]
        if row_scalar[i] >= 0:
            A[i, n_models * p + row_scalar[i]] = -1.0
    Q = np.linalg.inv((A.T * w) @ A)
    groups = np.arange(n_scalar).reshape(-1, 3)
    blocks = scalar_cofactors(sol, groups)
    for g, idx in enumerate(groups):
        k = n_models * p + idx
        np.testing.assert_allclose(blocks[g], Q[np.ix_(k, k)], rtol=1e-8, atol=1e-12)


def test_planimetric_theory_matches_simulation():
    # 100 simulated blocks: the RMS of the true errors estimates μ to ~1/sqrt(2·100·Neff)
    # with Neff ≥ 1 independent errors per block, i.e. better than 7 %; allow 10 %.
    p = planimetric_precision(3, replicates=100, rng=np.random.default_rng(5))
    assert p.empirical == pytest.approx(p.mu, rel=0.10)
    assert p.sd.shape[1] == 2 and np.all(p.sd > 0)


def test_logarithmic_law_and_bound():
    strips = (2, 4, 8, 12)
    mu = [planimetric_precision(n).mu for n in strips]
    assert max(mu) < 2.0  # Ackermann §17: μ_xy < 2 σ0
    assert mu[-1] > mu[1]  # grows with the block size …
    a, b = fit_log_law(strips, mu)
    assert b > 0
    fitted = a + b * np.log10(strips)
    assert np.max(np.abs(fitted - mu)) < 0.05  # … logarithmically


def test_fit_log_law_recovers_coefficients():
    n = np.array([2, 5, 10, 40])
    a, b = fit_log_law(n, 0.9 + 0.2 * np.log10(n))
    assert (a, b) == pytest.approx((0.9, 0.2))


def test_height_accuracy_grows_with_chain_spacing():
    mu = [height_precision(i, n_strips=3, models_per_strip=12).mu for i in (2, 4, 6, 12)]
    assert all(x < y for x, y in zip(mu, mu[1:]))
    # Ackermann §19: bridging 4-5 bases, the block height is as good as a single model
    assert 0.8 < mu[1] < 1.5


def test_height_theory_matches_simulation():
    h = height_precision(
        4, n_strips=3, models_per_strip=12, replicates=100, rng=np.random.default_rng(2)
    )
    assert h.empirical == pytest.approx(h.mu, rel=0.10)
