"""A banded Cholesky factor of S in single precision, refined to double-precision steps.

The factorisation of the reduced camera system S is the largest single cost of a large
strip block's Gauss-Newton step (``dpbtrf``: n·b² flops for a half-bandwidth b). In
single precision LAPACK's ``spbtrf`` does the same work in about 0.6 of the time (half
the memory traffic, twice the SIMD width). A step solved with the single-precision
factor alone is off by about κ(S)·u₃₂ relative (u₃₂ ≈ 6e-8; on the bench's 2 100-image
block ≈ 5e-3), so each solve is followed by *iterative refinement* in double precision,
the scheme of LAPACK's mixed-precision drivers (``dsposv`` for dense matrices)::

    x₀ = L₃₂⁻ᵀ L₃₂⁻¹ b,    r_k = b − S x_k  (S and r in float64),    x_{k+1} = x_k + L₃₂⁻ᵀ L₃₂⁻¹ r_k

Each round shrinks the error by about κ(S)·u₃₂ and costs one product with S (its 6×6
blocks as a float64 block-sparse matrix, ≈ 2 ms on the large block) and one single-precision
band solve (≈ 1 ms), so two or three rounds bring the step to within
:data:`REFINE_TOLERANCE` of the double-precision one — far below anything the stopping
rule or the optimum can see. When the single-precision factorisation breaks down
(S too ill-conditioned for 24 bits) or the refinement does not contract by
:data:`REFINE_CONTRACTION` per round, S is factored in double precision after all
(:func:`orientviz.bundle._reduced.factor_reduced` decides; the refinement's own
fallback re-factors from the kept blocks).

Used only where the factor serves the steps alone (plain bundles without the precision
pass, whose cofactors need the double-precision factor) and where the band is wide
enough for the saving to exceed the refinement (:data:`MIN_BAND_FLOPS`).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg.lapack
import scipy.sparse as sp
from numpy.typing import NDArray

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: Refine until the last correction is at most this fraction of the solution (largest
#: element, each scaled by √S_ii: in conditional σ, the stopping rule's units).
REFINE_TOLERANCE: float = 1e-7
#: Each round must shrink the correction at least by this factor, else double precision.
REFINE_CONTRACTION: float = 0.25
#: At most this many refinement rounds.
MAX_ROUNDS: int = 6
#: Single precision only when the band factorisation's n·kd² flops reach this: below,
#: the refinement's products cost about what the cheaper factorisation saves.
MIN_BAND_FLOPS: float = 2e8


class SymmetricBlocks:
    """S as a float64 block-sparse (BSR, 6×6 blocks) matrix from its blocks (i ≤ k).

    Parameters
    ----------
    block_i, block_k : ndarray of int, shape (nb,)
        Images of each block (i ≤ k), as in :class:`~orientviz.bundle.ReducedStructure`.
    n_cam : int
        Number of images m (S is 6m × 6m).
    """

    def __init__(self, block_i: I64, block_k: I64, n_cam: int) -> None:
        nb = block_i.size
        # both directions of every block, sorted by (row image, column image)
        off = np.flatnonzero(block_i != block_k)
        row = np.concatenate([block_i, block_k[off]])
        col = np.concatenate([block_k, block_i[off]])
        o = np.lexsort((col, row))
        self.n = 6 * n_cam
        self.indices = col[o].astype(np.int32)
        self.indptr = np.zeros(n_cam + 1, np.int32)
        self.indptr[1:] = np.cumsum(np.bincount(row, minlength=n_cam))
        self.source = np.concatenate([np.arange(nb), off])[o]  # block of each entry …
        # … transposed below the diagonal and on it (as dense_matrix: bit-equal entries)
        self.transposed = (o >= nb) | (row[o] == col[o])

    def matrix(self, blocks: F64) -> sp.bsr_matrix:
        """S (n, n) from its blocks (nb, 6, 6)."""
        data = blocks[self.source]
        data[self.transposed] = data[self.transposed].transpose(0, 2, 1)
        return sp.bsr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))


class MixedBandFactor:
    """Single-precision band factor of S with double-precision refinement.

    Parameters
    ----------
    c32 : ndarray, float32, shape (kd + 1, n)
        ``spbtrf``'s lower band factor (Fortran order), rows and columns in the band
        numbering.
    S : scipy.sparse.bsr_matrix
        S in float64, original numbering.
    perm : ndarray of int, shape (n,)
        Band numbering: original index of each band position.
    refactor : callable
        Returns the double-precision :class:`~orientviz.bundle._reduced.Factor`, used
        when the refinement does not contract.
    """

    def __init__(self, c32, S: sp.bsr_matrix, perm: I64, refactor) -> None:
        self.c32, self.S, self.perm, self._refactor = c32, S, perm, refactor
        # corrections are judged in units of S's diagonal (conditional σ: the stopping
        # rule's units), so metres and radians weigh alike
        self.d = np.sqrt(np.abs(S.diagonal()))
        self.fallback = None
        self.rounds: list[int] = []  #: refinement rounds of each solve (diagnostics)

    def _solve32(self, rhs: F64) -> F64:
        p = self.perm
        z, info = scipy.linalg.lapack.spbtrs(
            self.c32, rhs[p].astype(np.float32), lower=1, overwrite_b=1
        )
        if info != 0:  # pragma: no cover - arguments are ours
            raise ValueError(f"spbtrs: illegal argument {-info}")
        out = np.empty(z.shape)
        out[p] = z
        return out

    def solve(self, rhs: F64) -> F64:
        """S⁻¹ rhs to :data:`REFINE_TOLERANCE` (rhs (n,) or (n, k))."""
        if self.fallback is not None:
            return self.fallback.solve(rhs)
        x = self._solve32(rhs)
        d = self.d if rhs.ndim == 1 else self.d[:, None]
        scale = float(np.max(np.abs(x) * d, initial=0.0))
        last = 0.4 * scale  # the first correction must be below 0.1 of the solution
        for k in range(1, MAX_ROUNDS + 1):
            dx = self._solve32(rhs - self.S @ x)
            x += dx
            size = float(np.max(np.abs(dx) * d, initial=0.0))
            if not np.isfinite(size) or size > REFINE_CONTRACTION * last:
                break  # no contraction: double precision after all
            if size <= REFINE_TOLERANCE * scale:
                self.rounds.append(k)
                return x
            last = size
        self.fallback = self._refactor()
        self.rounds.append(-1)
        return self.fallback.solve(rhs)


def mixed_band_factor(st, blocks: F64, refactor) -> MixedBandFactor | None:
    """Factor S in single precision; None when ``spbtrf`` breaks down.

    Parameters
    ----------
    st : ReducedStructure
        A banded structure (:class:`~orientviz.bundle.ReducedStructure`: its band
        numbering, half-bandwidth and the destinations of S's entries in the band); the
        block pattern of S for the refinement's products is kept on it.
    blocks : ndarray, shape (nb, 6, 6)
        S's blocks (float64).
    refactor : callable
        The double-precision factorisation, for :class:`MixedBandFactor`'s fallback.
    """
    n, kd = st.n_reduced, st.kd
    if st._symmetric is None:
        st._symmetric = SymmetricBlocks(st.block_i, st.block_k, st.n_cam)
    ab = np.zeros(n * (kd + 1) + 1, np.float32)  # + the spare slot (see ReducedStructure._setup_solver)
    ab[st.band_dst] = blocks.reshape(-1)
    c, info = scipy.linalg.lapack.spbtrf(ab[:-1].reshape(n, kd + 1).T, lower=1, overwrite_ab=1)
    if info != 0 or not np.isfinite(c[0]).all():
        return None
    return MixedBandFactor(c, st._symmetric.matrix(blocks), st.scalar_perm, refactor)
