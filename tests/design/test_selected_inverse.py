"""The banded selected inverse the designs use (the bundle's,
:func:`orientviz.bundle.precision.banded_selected_inverse`) equals the dense inverse inside
the band, also when its window moves many times."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from orientviz.bundle.precision import banded_selected_inverse


def _band_matrix(n: int, kd: int, rng) -> np.ndarray:
    """A random symmetric positive definite matrix with half-bandwidth kd."""
    A = rng.standard_normal((n, n))
    i, j = np.indices((n, n))
    S = np.where(np.abs(i - j) <= kd, A + A.T, 0.0)
    return S + (2.0 * kd + 2.0) * np.eye(n)  # beyond the band part's spectral radius


@pytest.mark.parametrize(
    ("n", "kd", "nb"),
    [(50, 7, 5), (300, 40, 16), (101, 100, 48), (997, 23, 7), (40, 60, 48), (9, 2, 1)],
)
def test_the_selected_inverse_is_the_inverse_inside_the_band(n, kd, nb):
    """Entries Z[i, i + d] (d ≤ kd) of S⁻¹ from the band factor, zero beyond n; a small
    the window (2 block rows) moves back many times (997 rows: 143 block rows)."""
    rng = np.random.default_rng(n + kd)
    kd = min(kd, n - 1)
    S = _band_matrix(n, kd, rng)
    ab = np.zeros((kd + 1, n))
    for d in range(kd + 1):
        ab[d, : n - d] = np.diagonal(S, -d)
    cb = scipy.linalg.cholesky_banded(ab, lower=True)
    Z = np.linalg.inv(S)
    ref = np.zeros((n, kd + 1))
    for d in range(kd + 1):
        ref[: n - d, d] = np.diagonal(Z, d)
    got = banded_selected_inverse(cb, nb, window=2)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12 * np.abs(Z).max())
