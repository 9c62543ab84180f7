"""The banded selected inverse of a design's reduced system, with BLAS on views.

:func:`selected_inverse` computes what
:func:`orientviz.bundle.precision.banded_selected_inverse` computes — the entries of
Z = S⁻¹ inside the band from the banded Cholesky factor L (S = L Lᵀ) by the block form of
Takahashi's recursion, block row I from the bottom up with the rows B below it in the
band:

    Z_IB = −L_II⁻ᵀ L_BIᵀ Z_BB,     Z_II = L_II⁻ᵀ (L_II⁻¹ − L_BIᵀ Z_IBᵀ)

— with the same operations in the same order, but laid out so that no block is copied
before BLAS reads it:

* L is copied once into LAPACK's band storage with ``nb`` zero rows below each column
  (column stride kd + 1 + nb): then L_BIᵀ and L_IIᵀ of every block row are plain strided
  views (row stride kd + nb, unit column stride) that BLAS reads in place, the zero rows
  standing for the entries beyond the band and above the diagonal;
* Z lives in a square window that slides up the diagonal of one buffer: the Z_BB a block
  row reads is the part its predecessor wrote, a view; only every few block rows the
  window is moved back to the buffer's end (one copy of Z_BB).

The cost is the recursion's 2·n·kd² flops at matrix-product speed.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

F64 = NDArray[np.float64]

#: Block rows per position of the sliding window before it is moved back (one copy of
#: Z_BB each time).
WINDOW_BLOCKS: int = 12


def _view(flat: F64, start: int, shape: tuple[int, int], row_stride: int) -> F64:
    """A read-only (rows, cols) view of ``flat`` from element ``start``: rows step by
    ``row_stride`` elements, columns by one."""
    e = flat.itemsize
    return np.lib.stride_tricks.as_strided(
        flat[start:], shape=shape, strides=(row_stride * e, e), writeable=False
    )


def selected_inverse(cb: F64, nb: int = 48) -> F64:
    """Entries of S⁻¹ inside the band from the banded Cholesky factor of S.

    Parameters
    ----------
    cb : ndarray, shape (kd + 1, n)
        Lower banded Cholesky factor (``scipy.linalg.cholesky_banded(..., lower=True)``):
        ``cb[d, j] = L[j + d, j]``.
    nb : int
        Block size of the recursion (rows).

    Returns
    -------
    ndarray, shape (n, kd + 1)
        ``Zb[i, d] = (S⁻¹)[i, i + d]`` (upper band by rows; zero beyond n), as
        :func:`orientviz.bundle.precision.banded_selected_inverse` returns it.
    """
    kd, n = cb.shape[0] - 1, cb.shape[1]
    nb = max(1, min(nb, n))
    C = kd + 1 + nb  # column stride of the padded factor
    # one leading zero column: the view of L_IIᵀ of the first block reads before column 0
    pad = np.zeros((n + 1, C))
    pad[1:, : kd + 1] = cb.T
    flat = pad.reshape(-1)

    def at(d: int, j: int) -> int:  # element L[j + d, j] of the padded storage
        return (j + 1) * C + d

    T = WINDOW_BLOCKS * nb + kd + nb  # the window buffer's size
    buf = np.zeros((T, T + kd + 1))
    off = max(n - T, 0)  # buffer index = global index − off
    Zb = np.empty((n, kd + 1))
    bflat = buf.reshape(-1)
    W = buf.shape[1]
    for i0 in reversed(range(0, n, nb)):
        i1 = min(i0 + nb, n)
        b1 = min(i1 + kd, n)
        ni, nbb = i1 - i0, b1 - i1
        if i0 < off:  # move the window (its Z_BB) back to the buffer's end
            new = max(b1 - T, 0)
            s, t = i1 - off, i1 - new
            buf[t : t + nbb, t : t + nbb] = buf[s : s + nbb, s : s + nbb].copy()
            off = new
        q = i0 - off
        LIIt = _view(flat, at(0, i0), (ni, ni), C - 1)  # L_IIᵀ, upper triangular
        LIIinv = scipy.linalg.solve_triangular(
            LIIt, np.eye(ni), lower=False, trans="T", check_finite=False
        )  # L_II⁻¹ = (L_IIᵀ)⁻ᵀ
        if nbb:
            LBIt = _view(flat, at(i1 - i0, i0), (ni, nbb), C - 1)  # L_BIᵀ
            ZBB = buf[q + ni : q + ni + nbb, q + ni : q + ni + nbb]
            ZIB = LIIinv.T @ (LBIt @ ZBB)
            np.negative(ZIB, out=ZIB)
            buf[q : q + ni, q + ni : q + ni + nbb] = ZIB
            buf[q + ni : q + ni + nbb, q : q + ni] = ZIB.T
            buf[q : q + ni, q : q + ni] = LIIinv.T @ (LIIinv - LBIt @ ZIB.T)
        else:
            buf[q : q + ni, q : q + ni] = LIIinv.T @ LIIinv
        # the band rows i0 … i1 − 1: Z[i, i + d] at buffer (q + r, q + r + d); beyond
        # b1 only for the last rows (b1 = n), which are written first, into the
        # buffer's zeros
        Zb[i0:i1] = _view(bflat, q * W + q, (ni, kd + 1), W + 1)
    return Zb
