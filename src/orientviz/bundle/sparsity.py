"""The block structure of a bundle's normal equations, at teaching size.

Unknowns ordered as 6 exterior-orientation elements per image (X0, Y0, Z0 in m; ω, φ, κ
in rad), then 3 coordinates per unknown point (m). With the weights P = diag(1/σ²) the
normal equations are

    [ U   W ] [dc]   [bc]      U = diag(U_i)  (6×6 per image)
    [ Wᵀ  V ] [dp] = [bp]      V = diag(V_j)  (3×3 per point),  W_ij ≠ 0 iff image i sees point j.

:func:`bundle_normal_blocks` assembles U, W, V and the right sides for a
:class:`~orientviz.block.Block` (dense W: a few hundred images at most — the real solver
is :mod:`orientviz.bundle.reduced`). :func:`block_pattern`, :func:`reduced_pattern`,
:func:`bandwidth` and :func:`cholesky_fill` describe the sparsity (in blocks): the reduced
system S = U − W V⁻¹ Wᵀ has a non-zero block (i, k) exactly when images i and k see a
common point, and a Cholesky factor of S fills the band between its outermost non-zeros.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..camera import collinearity_jacobian

if TYPE_CHECKING:  # annotations only
    from ..block import Block

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]
B8 = NDArray[np.bool_]


@dataclass
class BundleNormal:
    """Normal-equation blocks of a bundle block at the current values.

    Attributes
    ----------
    U : ndarray, shape (m, 6, 6)
        Image blocks, per image.
    W : ndarray, shape (6m, 3q)
        Image-point coupling (dense).
    V : ndarray, shape (q, 3, 3)
        Point blocks, per unknown point.
    bc : ndarray, shape (6m,)
    bp : ndarray, shape (3q,)
        Right sides JᵀP(l − f).
    unknown_point : ndarray of int, shape (p,)
        Index of each block point among the q unknown points, −1 if held fixed.
    obs_image, obs_unknown : ndarray of int, shape (n,)
        Image and unknown-point index (−1: fixed point) of each ray.
    vtpv : float
        Weighted sum of squares (l − f)ᵀP(l − f) at the current values.
    """

    U: F64
    W: F64
    V: F64
    bc: F64
    bp: F64
    unknown_point: I64
    obs_image: I64
    obs_unknown: I64
    vtpv: float

    @property
    def n_images(self) -> int:
        return int(self.U.shape[0])

    @property
    def n_points(self) -> int:
        return int(self.V.shape[0])

    def dense(self) -> tuple[F64, F64]:
        """The whole normal matrix N (6m + 3q square) and right side b, dense."""
        m, q = self.n_images, self.n_points
        N = np.zeros((6 * m + 3 * q,) * 2)
        for i in range(m):
            N[6 * i : 6 * i + 6, 6 * i : 6 * i + 6] = self.U[i]
        for j in range(q):
            s = 6 * m + 3 * j
            N[s : s + 3, s : s + 3] = self.V[j]
        N[: 6 * m, 6 * m :] = self.W
        N[6 * m :, : 6 * m] = self.W.T
        return N, np.concatenate([self.bc, self.bp])


def bundle_normal_blocks(block: Block) -> BundleNormal:
    """Assemble the normal-equation blocks of ``block`` at its current values.

    Points whose three coordinates all have σ = 0 (fixed control) are not unknowns.
    Weights are 1/σ² of the observations (mm); one camera (c, x0, y0) per image from
    ``block.cameras``.
    """
    obs, img, pts = block.observations, block.images, block.points
    cam = img.camera[obs.image]
    fixed = np.all(np.nan_to_num(pts.sigma, nan=1.0) == 0.0, axis=1)
    unknown = np.full(len(pts), -1, dtype=np.int64)
    unknown[~fixed] = np.arange(int(np.sum(~fixed)))
    xy, Je, Jp, _ = collinearity_jacobian(
        pts.xyz[obs.point], img.X0[obs.image], img.angles[obs.image], block.cameras.c[cam],
        block.cameras.x0[cam], block.cameras.y0[cam], block.sequence,
    )  # fmt: skip
    w = 1.0 / np.asarray(obs.sigma, dtype=float) ** 2  # (n, 2)
    r = obs.xy - xy  # l − f, mm
    m, q = len(img), int(np.sum(~fixed))
    PJe = Je * w[:, :, None]
    U = np.zeros((m, 6, 6))
    np.add.at(U, obs.image, np.einsum("nki,nkj->nij", PJe, Je))
    bc = np.zeros((m, 6))
    np.add.at(bc, obs.image, np.einsum("nki,nk->ni", Je, w * r))
    oq = unknown[obs.point]
    use = oq >= 0
    V = np.zeros((q, 3, 3))
    PJp = Jp * w[:, :, None]
    np.add.at(V, oq[use], np.einsum("nki,nkj->nij", PJp[use], Jp[use]))
    bp = np.zeros((q, 3))
    np.add.at(bp, oq[use], np.einsum("nki,nk->ni", Jp[use], (w * r)[use]))
    W = np.zeros((6 * m, 3 * q))
    Wb = np.einsum("nki,nkj->nij", PJe[use], Jp[use])  # (n_use, 6, 3)
    for (i, j), blk in zip(zip(obs.image[use], oq[use]), Wb):
        W[6 * i : 6 * i + 6, 3 * j : 3 * j + 3] += blk
    return BundleNormal(U, W, V, bc.reshape(-1), bp.reshape(-1), unknown, obs.image.copy(), oq,
                        float(np.sum(w * r * r)))  # fmt: skip


def block_pattern(obs_image: ArrayLike, obs_unknown: ArrayLike, n_images: int, n_points: int) -> B8:
    """Non-zero blocks of the whole normal matrix, (m + q) square: images first, then points."""
    oi = np.asarray(obs_image, dtype=int)
    oq = np.asarray(obs_unknown, dtype=int)
    n = n_images + n_points
    P = np.zeros((n, n), dtype=bool)
    P[np.arange(n), np.arange(n)] = True
    use = oq >= 0
    P[oi[use], n_images + oq[use]] = True
    P[n_images + oq[use], oi[use]] = True
    return P


def reduced_pattern(obs_image: ArrayLike, obs_unknown: ArrayLike, n_images: int) -> B8:
    """Non-zero 6×6 blocks of S = U − W V⁻¹ Wᵀ: images that see a common unknown point."""
    oi = np.asarray(obs_image, dtype=int)
    oq = np.asarray(obs_unknown, dtype=int)
    use = oq >= 0
    import scipy.sparse as sp

    q = int(oq.max(initial=-1)) + 1
    A = sp.csr_matrix((np.ones(int(use.sum())), (oi[use], oq[use])), shape=(n_images, max(q, 1)))
    S = (A @ A.T).toarray() > 0
    S[np.arange(n_images), np.arange(n_images)] = True
    return S


def bandwidth(pattern: ArrayLike, order: ArrayLike | None = None) -> int:
    """Half-bandwidth max abs(i − k) over the non-zeros of a symmetric pattern (in blocks),
    after renumbering by ``order`` (new position → old index)."""
    P = np.asarray(pattern, dtype=bool)
    if order is not None:
        o = np.asarray(order, dtype=int)
        P = P[np.ix_(o, o)]
    i, k = np.nonzero(P)
    return int(np.max(np.abs(i - k), initial=0))


def cholesky_fill(pattern: ArrayLike, order: ArrayLike | None = None) -> B8:
    """Pattern of the lower Cholesky factor L of a symmetric pattern (symbolic elimination).

    Column k of L holds the non-zeros of column k of the (reordered) matrix below the
    diagonal plus those of every earlier column whose first off-diagonal non-zero is k
    (its parent in the elimination tree). Entries of L that are zero in the matrix are
    the *fill-in*.
    """
    P = np.asarray(pattern, dtype=bool)
    if order is not None:
        o = np.asarray(order, dtype=int)
        P = P[np.ix_(o, o)]
    n = P.shape[0]
    L = np.tril(P).copy()
    for k in range(n):
        below = np.flatnonzero(L[k + 1 :, k]) + k + 1
        if below.size:
            parent = below[0]
            L[below, parent] = True  # the structure of column k passes to its parent
    return L
