"""The band kernels' shared parts (orientviz.bundle.precision._band): one padded copy of
the factor serves the selected inverse and the solves (as ReducedInverse shares it), and
the triangular solve is LAPACK's (dtrtrs), as scipy's solve_triangular calls it."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from band_storage import lower_band
from orientviz.bundle.precision import BandSolver, banded_selected_inverse
from orientviz.bundle.precision._band import padded_band, tri_solve

CASES = [(50, 7, 5), (300, 40, 16), (101, 100, 48), (997, 23, 7), (40, 60, 48), (9, 2, 1)]


def _factor(n: int, kd: int, rng) -> tuple[np.ndarray, np.ndarray]:
    """A random symmetric positive definite band matrix S (half-bandwidth kd) and its
    lower band Cholesky factor."""
    A = rng.standard_normal((n, n))
    i, j = np.indices((n, n))
    S = np.where(np.abs(i - j) <= kd, A + A.T, 0.0)
    S = S + np.diag(np.abs(S).sum(axis=1) + 1.0)  # diagonally dominant: definite
    ab = lower_band(S, kd)
    return S, scipy.linalg.cholesky_banded(ab, lower=True)


@pytest.mark.parametrize(("n", "kd", "nb"), CASES)
def test_one_padded_copy_serves_the_inverse_and_the_solves(n, kd, nb):
    """The factor padded once with more zero rows than either block size
    (orientviz.bundle.precision._band.padded_band, as ReducedInverse shares it) gives the
    same inverse and solves as the dense computations."""
    rng = np.random.default_rng(5 * n + kd)
    kd = min(kd, n - 1)
    S, cb = _factor(n, kd, rng)
    pad = padded_band(cb, nb + 17)
    assert pad.shape == (n + 1, kd + 1 + nb + 17)
    Z = np.linalg.inv(S)
    ref = np.zeros((n, kd + 1))
    for d in range(kd + 1):
        ref[: n - d, d] = np.diagonal(Z, d)
    got = banded_selected_inverse(cb, nb, window=2, padded=pad)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12 * np.abs(Z).max())
    B = rng.standard_normal((n, 4))
    band = BandSolver(cb, max(1, nb - 1), padded=pad)
    np.testing.assert_allclose(band.solve(B), np.linalg.solve(S, B), rtol=1e-10, atol=1e-12)


def test_the_triangular_solve_is_lapacks_and_stops_at_a_zero_pivot():
    """tri_solve on the transpose of a C-ordered triangle equals scipy's
    solve_triangular on the triangle (both transposes); a zero pivot raises."""
    rng = np.random.default_rng(11)
    L = np.tril(rng.standard_normal((30, 30))) + 6.0 * np.eye(30)
    B = rng.standard_normal((30, 4))
    for trans in (0, 1):
        ref = scipy.linalg.solve_triangular(L, B, lower=True, trans=1 - trans)
        np.testing.assert_array_equal(tri_solve(L.T, B, False, trans), ref)
    L[7, 7] = 0.0
    with pytest.raises(np.linalg.LinAlgError):
        tri_solve(L.T, B, False, 0)
