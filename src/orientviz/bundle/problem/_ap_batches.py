"""The point-elimination terms of the additional parameters' border by point batches.

With a group of additional parameters per image (a BAL problem, COLMAP cameras per
image) a point's rays lie in as many groups as it has rays, and the terms that the
elimination of the points leaves in E and F (:mod:`._ap_normal`) couple thousands of
group pairs. They are formed here per point: the points with k rays and c (point, group)
pairs are stacked, one product gives all their (ray, pair) blocks ``T_a H_eᵀ`` (6 × k)
and (pair, pair) blocks ``H_e V⁻¹ H_e'ᵀ`` (k × k), and each block's rows are added
into the block of E or F they belong to by ``np.bincount`` over the blocks' indices
(computed once per problem).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: Entries of the largest per-point product of one batch (:func:`point_batches`): its
#: temporaries stay in the cache.
BATCH_DOUBLES: int = 2**16
#: The batches' row indices (:class:`PointBatch`) are kept when they take at most this
#: many bytes (Ladybug, 31 812 rays: 7.7 MB); beyond (long tracks: the 177-image COLMAP
#: model would need ~150 MB) they are formed anew in each formation from the block indices.
ROWS_KEPT_BYTES: int = 2**24


class PointBatch(NamedTuple):
    """Points with k rays and c (point, group) pairs, for the per-point products.

    ``rays`` (n, k) their rays (observations), ``pairs`` (n, c) their pairs. ``e_block``
    (n, k, c): for the product block (ray a, pair e), the index of E's other-group block
    (``APStructure.e_key``) it adds into, K (dropped) when e is a's own group;
    ``f_block`` (n, c, c): for the block (pair e, pair e'), F's group block g_e · G + g_e'.
    ``e_rows`` (n·k·6·c,), ``f_rows`` (n·c·k·c,): the rows 6·e_block + r and
    k·f_block + s that the products' rows add into, in their order (None where
    :data:`ROWS_KEPT_BYTES` does not hold them: then :func:`batch_rows` forms them).
    """

    rays: I64
    pairs: I64
    e_block: NDArray[np.int32]
    f_block: NDArray[np.int32]
    e_rows: NDArray[np.int32] | None = None
    f_rows: NDArray[np.int32] | None = None


def batch_rows(b: PointBatch, k: int) -> tuple[NDArray[np.int32], NDArray[np.int32]]:
    """The rows of E's and F's blocks that the products of batch ``b`` add into."""
    if b.e_rows is not None:
        return b.e_rows, b.f_rows
    r6 = np.arange(6, dtype=np.int32)[:, None]
    rk = np.arange(k, dtype=np.int32)[:, None]
    e_rows = (6 * b.e_block[:, :, None, :] + r6).reshape(-1)
    f_rows = (k * b.f_block[:, :, None, :] + rk).reshape(-1)
    return e_rows, f_rows


def point_batches(
    oi: I64, go: I64, vo: I64, ocol: I64, first: I64, count: I64, A, k: int
) -> list[PointBatch]:
    """The :class:`PointBatch` es of a problem: points grouped by (rays, pairs), in
    chunks of at most :data:`BATCH_DOUBLES` entries of E's product.

    Parameters
    ----------
    oi, go : ndarray of int, shape (n,)
        Image and group of each observation.
    vo : ndarray of int
        Observations of point unknowns, sorted by point.
    ocol : ndarray of int, shape (n,)
        Point unknown of each observation.
    first, count : ndarray of int, shape (p,)
        Each point's first (point, group) pair and its number of pairs.
    A : APStructure
        With ``G``, ``pg_grp`` and ``e_key`` set.
    k : int
        Parameters per group.
    """
    G, n_pt = A.G, first.size
    pts_of = ocol[vo]
    rcount = np.bincount(pts_of, minlength=n_pt)
    rfirst = np.cumsum(rcount) - rcount
    key = rcount * (int(count.max(initial=0)) + 1) + count
    order = np.argsort(key, kind="stable")
    bounds = np.flatnonzero(np.diff(key[order])) + 1
    K = A.e_key.size
    out = []
    for grp_pts in np.split(order, bounds):
        if grp_pts.size == 0:
            continue
        kr, c = int(rcount[grp_pts[0]]), int(count[grp_pts[0]])
        step = max(1, BATCH_DOUBLES // (6 * kr * k * c))
        for c0 in range(0, grp_pts.size, step):
            pts = grp_pts[c0 : c0 + step]
            n = pts.size
            rays = vo[rfirst[pts][:, None] + np.arange(kr)]
            pairs = first[pts][:, None] + np.arange(c)
            # E: block (point, ray a, pair e) → E's block (image of a, group of e), or K
            # when e is a's own group
            shape = (n, kr, c)
            g_e = np.broadcast_to(A.pg_grp[pairs][:, None, :], shape)
            g_a = np.broadcast_to(go[rays][:, :, None], shape)
            i_a = np.broadcast_to(oi[rays][:, :, None], shape)
            other = g_e != g_a
            e_block = np.full(shape, K, np.int32)
            e_block[other] = np.searchsorted(A.e_key, i_a[other] * G + g_e[other])
            # F: block (point, pair e, pair e') → (g_e, g_e')
            gp = A.pg_grp[pairs]
            f_block = (gp[:, :, None] * G + gp[:, None, :]).astype(np.int32)
            out.append(PointBatch(rays, pairs, e_block, f_block))
    size = sum(4 * (6 + k) * b.e_block.size for b in out)  # e_rows 6×, f_rows ≤ k× e_block
    if size <= ROWS_KEPT_BYTES:
        out = [b._replace(**dict(zip(("e_rows", "f_rows"), batch_rows(b, k)))) for b in out]
    return out


def batched_terms(A, T: F64, H: F64, HV: F64, k: int) -> tuple[F64, F64]:
    """Σ T_a H_eᵀ into E's other-group blocks (K, 6, k) and Σ H_e V⁻¹ H_e'ᵀ into F's
    group blocks (G², k, k), over all rays a and pairs e, e' of each point: one stacked
    product per batch of points (:class:`PointBatch`)."""
    nE, nF = 6 * A.e_key.size, A.G * A.G * k
    other = np.zeros((k, nE + 6))
    F = np.zeros((k, nF))
    for b in A.batches:
        n, kr = b.rays.shape
        c = b.pairs.shape[1]
        pairs = b.pairs.reshape(-1)
        Hb = H[pairs].reshape(n, c * k, 3)
        e_rows, f_rows = batch_rows(b, k)
        if nE:
            Tb = T[b.rays.reshape(-1)].reshape(n, 6 * kr, 3)
            # (n, kr·6, c·k): column s of the rows (a, r, e), each into row 6·block + r
            P = np.matmul(Tb, Hb.transpose(0, 2, 1)).reshape(-1, k)
            rows = e_rows.astype(np.intp)  # (bincount's index type: converted once)
            for s in range(k):
                other[s] += np.bincount(rows, P[:, s], nE + 6)
        HVb = HV[pairs].reshape(n, c * k, 3)
        P = np.matmul(HVb, Hb.transpose(0, 2, 1)).reshape(-1, k)  # (n, c·k, c·k)
        rows = f_rows.astype(np.intp)
        for s in range(k):
            F[s] += np.bincount(rows, P[:, s], nF)
    return other[:, :nE].T.reshape(-1, 6, k), F.T.reshape(-1, k, k)
