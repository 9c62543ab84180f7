"""The band kernels the designs use (the bundle's precision): the selected inverse
(:func:`orientviz.bundle.precision.banded_selected_inverse`) equals the dense inverse inside
the band, also when its window moves many times; the solves with many columns
(:class:`orientviz.bundle.precision.BandSolver`) equal dense solves."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from band_storage import lower_band
from orientviz.bundle.precision import BandSolver, banded_selected_inverse


def _band_matrix(n: int, kd: int, rng) -> np.ndarray:
    """A random symmetric positive definite matrix with half-bandwidth kd."""
    A = rng.standard_normal((n, n))
    i, j = np.indices((n, n))
    S = np.where(np.abs(i - j) <= kd, A + A.T, 0.0)
    return S + np.diag(np.abs(S).sum(axis=1) + 1.0)  # diagonally dominant: definite


CASES = [(50, 7, 5), (300, 40, 16), (101, 100, 48), (997, 23, 7), (40, 60, 48), (9, 2, 1)]


def _factor(n: int, kd: int, rng) -> tuple[np.ndarray, np.ndarray]:
    """A band matrix S and its lower band Cholesky factor."""
    S = _band_matrix(n, kd, rng)
    ab = lower_band(S, kd)
    return S, scipy.linalg.cholesky_banded(ab, lower=True)


@pytest.mark.parametrize(("n", "kd", "nb"), CASES)
def test_the_selected_inverse_is_the_inverse_inside_the_band(n, kd, nb):
    """Entries Z[i, i + d] (d ≤ kd) of S⁻¹ from the band factor, zero beyond n; a small
    window (2 block rows) moves back many times (997 rows: 143 block rows)."""
    rng = np.random.default_rng(n + kd)
    kd = min(kd, n - 1)
    S, cb = _factor(n, kd, rng)
    Z = np.linalg.inv(S)
    ref = np.zeros((n, kd + 1))
    for d in range(kd + 1):
        ref[: n - d, d] = np.diagonal(Z, d)
    got = banded_selected_inverse(cb, nb, window=2)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12 * np.abs(Z).max())


@pytest.mark.parametrize(("n", "kd", "nb"), CASES)
def test_the_band_solves_equal_dense_solves(n, kd, nb):
    """S⁻¹B, L⁻¹B and L⁻ᵀB with 5 columns (and one vector) against dense solves."""
    rng = np.random.default_rng(3 * n + kd)
    kd = min(kd, n - 1)
    S, cb = _factor(n, kd, rng)
    L = np.linalg.cholesky(S)
    B = rng.standard_normal((n, 5))
    band = BandSolver(cb, nb)
    tol = dict(rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(band.solve(B), np.linalg.solve(S, B), **tol)
    np.testing.assert_allclose(band.forward(B), np.linalg.solve(L, B), **tol)
    np.testing.assert_allclose(band.backward(B.copy()), np.linalg.solve(L.T, B), **tol)
    np.testing.assert_allclose(band.solve(B[:, 0]), np.linalg.solve(S, B[:, 0]), **tol)


@pytest.mark.parametrize(("n", "kd", "nb"), CASES)
def test_the_selected_entries_asked_for(n, kd, nb):
    """``at=(rows, cols)``: the entries Z[rows, cols] inside the band (either triangle),
    read from the window as the recursion passes them; one outside the band raises."""
    rng = np.random.default_rng(7 * n + kd)
    kd = min(kd, n - 1)
    S, cb = _factor(n, kd, rng)
    Z = np.linalg.inv(S)
    rows = rng.integers(0, n, 400)
    cols = np.clip(rows + rng.integers(-kd, kd + 1, 400), 0, n - 1)
    got = banded_selected_inverse(cb, nb, window=2, at=(rows.reshape(20, 20), cols.reshape(20, 20)))
    np.testing.assert_allclose(
        got, Z[rows, cols].reshape(20, 20), rtol=0, atol=1e-12 * np.abs(Z).max()
    )
    if kd + 1 < n:
        with pytest.raises(ValueError, match="outside the band"):
            banded_selected_inverse(cb, nb, at=(np.array([0]), np.array([kd + 1])))
