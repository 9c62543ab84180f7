"""Forming the reduced camera system S = U − Σ_j W_j V_j⁻¹ W_jᵀ (the Schur complement).

Two ways, same S up to rounding (:func:`orientviz.bundle._solver_choice.choose_formation`
picks one per structure):

* by pairs of rays (a, b) of the same point: block (image(a), image(b)) gains
  T_a W_bᵀ (T = W V⁻¹). Only the non-zero blocks are touched, which is what banded and
  sparse systems need; the cost is Σ_j k_j(k_j + 1)/2 pairs for points seen k_j times,
  formed per point by one batched BLAS product of the points of equal track length
  (:func:`orientviz.bundle._tracks.schur_blocks`).
* :func:`dense_schur` — for a dense S (small or densely connected networks): with the
  Cholesky factor V_j = L_j L_jᵀ of each point block, Y_a = W_a L_j⁻ᵀ gives
  W_j V_j⁻¹ W_jᵀ = Y_j Y_jᵀ, so Σ_j over a chunk of points is one product Y Yᵀ of a
  (6m × 3p_chunk) matrix — BLAS ``dsyrk``, about 20 × the speed per flop of the
  pair-wise products. A network whose points are each seen by every image (pycolmap's
  ``visibility`` tracks) has Σ k_j² = m²·p: then the dense form does the same work.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg.blas as _blas
from numpy.typing import NDArray

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: Bytes of one chunk of the dense coupling matrix Y (6m × 3p_chunk) of :func:`dense_schur`.
DENSE_CHUNK_BYTES: int = 32 * 2**20


def gram_by_segments(J: F64, starts: I64, present: I64, m: int) -> F64:
    """Σ JᵀJ over the rays of each segment (image): U (m, 6, 6) from J (n, 2, 6).

    J holds the rays sorted by segment, ``starts`` where each non-empty segment begins,
    ``present`` which segment that is. One BLAS product (6 × 2k)(2k × 6) per segment of k
    rays: per-ray 6 × 6 products summed afterwards cost ~15 × more (a (n, 6, 6)
    intermediate and one tiny BLAS call per ray).
    """
    U = np.zeros((m, J.shape[2], J.shape[2]))
    A = J.reshape(-1, J.shape[2])
    bounds = np.append(starts, J.shape[0]) * J.shape[1]
    for s, (a, b) in enumerate(zip(bounds[:-1].tolist(), bounds[1:].tolist())):
        seg = A[a:b]
        U[present[s]] = seg.T @ seg
    return U


def whitened_couplings(W: F64, V: F64, column: I64) -> F64:
    """Y_a = W_a L_j⁻ᵀ per ray (n, 6, 3), V_j = L_j L_jᵀ (Cholesky of the 3 × 3 blocks).

    Y_a Y_bᵀ = W_a V_j⁻¹ W_bᵀ for rays a, b of point j = ``column[a]``. A block V_j that
    is not positive definite gives NaN (the factorisation of S then reports it).
    """
    a, b, c = V[:, 0, 0], V[:, 0, 1], V[:, 0, 2]
    d, e, f = V[:, 1, 1], V[:, 1, 2], V[:, 2, 2]
    with np.errstate(invalid="ignore", divide="ignore"):
        l00 = np.sqrt(a)
        l10, l20 = b / l00, c / l00
        l11 = np.sqrt(d - l10 * l10)
        l21 = (e - l20 * l10) / l11
        l22 = np.sqrt(f - l20 * l20 - l21 * l21)
        # Y Lᵀ = W row by row: forward substitution with L (per ray's point)
        L = np.stack([l00, l10, l20, l11, l21, l22], axis=1)[column]
        Y = np.empty_like(W)
        Y[:, :, 0] = W[:, :, 0] / L[:, None, 0]
        Y[:, :, 1] = (W[:, :, 1] - L[:, None, 1] * Y[:, :, 0]) / L[:, None, 3]
        Y[:, :, 2] = (W[:, :, 2] - L[:, None, 2] * Y[:, :, 0] - L[:, None, 4] * Y[:, :, 1]) / L[
            :, None, 5
        ]
    return Y


def dense_schur(st, U: F64, W: F64, V: F64, column: I64, image: I64) -> tuple[F64, F64]:
    """S formed densely by chunks of points: S = U − Σ_chunks Y Yᵀ (lower triangle).

    Parameters
    ----------
    st : orientviz.bundle._reduced.ReducedStructure
        The structure (``pt_obs``, ``pt_starts``: the rays of each point unknown; the
        blocks to return).
    U : ndarray, shape (m, 6, 6)
        Diagonal image blocks (damped).
    W : ndarray, shape (n, 6, 3)
        W_a = J_eᵀ P J_p per observation.
    V : ndarray, shape (p_var, 3, 3)
        Point blocks (damped).
    column, image : ndarray of int, shape (n,)
        Point unknown and image of each observation.

    Returns
    -------
    blocks : ndarray, shape (n_blocks, 6, 6)
        The blocks (i ≤ k) of S (as :func:`orientviz.bundle._tracks.schur_blocks` returns
        them).
    S : ndarray, shape (6m, 6m), Fortran order
        S with a valid lower triangle (what the dense Cholesky reads and overwrites).
    """
    m, n = st.n_cam, 6 * st.n_cam
    rays = st.pt_obs  # sorted by point
    Y = whitened_couplings(W[rays], V, column[rays])
    S = np.zeros((n, n), order="F")
    r6 = np.arange(6)
    z = np.zeros((m, 6, 6), np.int64)
    d_rows = (z + 6 * np.arange(m)[:, None, None] + r6[None, :, None]).reshape(-1)
    d_cols = (z + 6 * np.arange(m)[:, None, None] + r6[None, None, :]).reshape(-1)
    S[d_rows, d_cols] = U.reshape(-1)
    pc = max(1, DENSE_CHUNK_BYTES // (8 * 18 * m))
    starts = np.append(st.pt_starts, rays.size)
    img, pt = image[rays], column[rays]
    for p0 in range(0, st.n_pt, pc):
        p1 = min(p0 + pc, st.n_pt)
        a0, a1 = starts[p0], starts[p1]
        Yd = np.zeros((m, 6, p1 - p0, 3))
        Yd[img[a0:a1], :, pt[a0:a1] - p0, :] = Y[a0:a1]
        Y2 = Yd.reshape(n, 3 * (p1 - p0))
        # S ← S − Y2 Y2ᵀ (lower): BLAS sees the C-ordered Y2 as its transpose
        S = _blas.dsyrk(-1.0, Y2.T, beta=1.0, c=S, trans=1, lower=1, overwrite_c=1)
    bi, bk = st.block_i, st.block_k
    rows = 6 * bk[:, None, None] + r6[None, None, :]  # block (i, k)[r, c] = S[6k + c, 6i + r]
    cols = 6 * bi[:, None, None] + r6[None, :, None]
    blocks = S[rows, cols]
    D = S[d_rows, d_cols].reshape(m, 6, 6)  # diagonal blocks: only their lower half is S
    D = np.tril(D) + np.tril(D, -1).transpose(0, 2, 1)
    blocks[st.diag_block] = D
    return blocks, S
