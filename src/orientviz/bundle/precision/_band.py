"""Solves with a banded Cholesky factor by BLAS on views of the factor (many columns).

:class:`BandSolver` keeps a factor L (S = L Lᵀ, LAPACK's lower band storage
``cb[d, j] = L[j + d, j]``) once in band storage with ``nb`` zero rows below each column
(column stride kd + 1 + nb). A block L[r0:r1, c0:c1] within the band is then a strided
view (rows step one element, columns kd + nb elements) that matrix products read in
place, the zero rows standing for the entries beyond the band and above the diagonal.
S⁻¹B is the forward solve by row blocks of ``nb`` rows,

    X_I = L_II⁻¹ (B_I − L_I,[I−kd, I) X_[I−kd, I)),

then the backward solve X_I = L_II⁻ᵀ (X_I − L_[I, I+kd),Iᵀ X_[I, I+kd)): per block one
product with all columns of B (BLAS level 3) and one small triangular solve.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.linalg.lapack import dtrtrs

F64 = NDArray[np.float64]


def tri_solve(a: F64, b: F64, lower: bool, trans: int) -> F64:
    """X with op(a) X = b for a triangular float64 ``a`` (op: none for ``trans`` 0, the
    transpose for 1): LAPACK's dtrtrs on ``a`` as given, the call that
    ``scipy.linalg.solve_triangular`` makes for the transpose of a C-ordered triangle,
    without its checks and wrapping (a new array; ``b`` is not changed).

    Raises
    ------
    numpy.linalg.LinAlgError
        If a diagonal element of ``a`` is zero.
    """
    x, info = dtrtrs(a, b, lower=int(lower), trans=trans)
    if info > 0:
        raise np.linalg.LinAlgError(f"singular matrix: resolution failed at diagonal {info - 1}")
    return x


def padded_band(cb: F64, nb: int) -> F64:
    """The factor in band storage with ``nb`` zero rows below each column, shape
    (n + 1, kd + 1 + nb): row j + 1 holds column j of L from its diagonal (``cb[:, j]``),
    row 0 is a zero column (read above L[0, 0]). Read by :class:`BandSolver` and
    :func:`orientviz.bundle.precision.banded_selected_inverse` with block sizes up to
    ``nb`` (one copy for both)."""
    kd, n = cb.shape[0] - 1, cb.shape[1]
    pad = np.empty((n + 1, kd + 1 + nb))
    pad[0] = 0.0
    pad[1:, : kd + 1] = cb.T
    pad[1:, kd + 1 :] = 0.0
    return pad


class BandSolver:
    """Solves S X = B with the banded Cholesky factor of S.

    Parameters
    ----------
    cb : ndarray, shape (kd + 1, n)
        Lower banded Cholesky factor (``scipy.linalg.cholesky_banded(..., lower=True)``).
    nb : int
        Rows per block of the solves.
    padded : ndarray, optional
        The factor as :func:`padded_band` gives it with at least ``nb`` zero rows (used
        in place, not copied); made here when not given.
    """

    def __init__(self, cb: F64, nb: int = 64, padded: F64 | None = None) -> None:
        kd, n = cb.shape[0] - 1, cb.shape[1]
        self.kd, self.n, self.nb = kd, n, max(1, min(nb, n))
        if padded is None or padded.shape[1] < kd + 1 + self.nb:
            padded = padded_band(cb, self.nb)
        self.C = padded.shape[1]
        self._flat = padded.reshape(-1)
        self._diag = [
            np.array(self._L(i0, min(i0 + self.nb, n), i0, min(i0 + self.nb, n)))
            for i0 in range(0, n, self.nb)
        ]

    def _L(self, r0: int, r1: int, c0: int, c1: int) -> F64:
        """L[r0:r1, c0:c1] (inside the band, or its zeros) as a read-only view."""
        e = self._flat.itemsize
        start = (c0 + 1) * self.C + (r0 - c0)
        v = np.ndarray((r1 - r0, c1 - c0), self._flat.dtype, self._flat, start * e,
                       (e, (self.C - 1) * e))  # fmt: skip
        v.flags.writeable = False
        return v

    def forward(self, B: F64) -> F64:
        """L⁻¹ B for B (n, k) (rows in the factor's order), a new C-ordered array."""
        kd, n, nb = self.kd, self.n, self.nb
        X = np.array(B, dtype=float, order="C").reshape(n, -1)
        for k, i0 in enumerate(range(0, n, nb)):
            i1, c0 = min(i0 + nb, n), max(i0 - kd, 0)
            if i0 > c0:
                X[i0:i1] -= self._L(i0, i1, c0, i0) @ X[c0:i0]
            X[i0:i1] = tri_solve(self._diag[k].T, X[i0:i1], False, 1)  # L_II⁻¹ X_I
        return X

    def backward(self, Y: F64) -> F64:
        """L⁻ᵀ Y for Y (n, k), in place when Y is C-ordered float (returned)."""
        kd, n, nb = self.kd, self.n, self.nb
        X = np.asarray(Y, dtype=float, order="C").reshape(n, -1)
        for k in reversed(range(len(self._diag))):
            i0 = k * nb
            i1, b1 = min(i0 + nb, n), min(i0 + nb + kd, n)
            if b1 > i1:
                X[i0:i1] -= self._L(i1, b1, i0, i1).T @ X[i1:b1]
            X[i0:i1] = tri_solve(self._diag[k].T, X[i0:i1], False, 0)  # L_II⁻ᵀ X_I
        return X

    def solve(self, B: F64) -> F64:
        """S⁻¹ B for B (n,) or (n, k) (rows in the factor's order)."""
        return self.backward(self.forward(B)).reshape(np.shape(B))
