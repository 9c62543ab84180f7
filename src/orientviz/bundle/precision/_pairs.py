"""Image–point cofactors by pairs of rays: Q_cp(i_a, j) = −Σ_b Q_cc(i_a, i_b) T_b.

The blocks Q_cc of the image pairs that share a point (the reduced structure's pairs
i ≤ k, d × d each) and T_b = W_b V_j⁻¹ (d × 3) per ray; for each ray a of a point j the
sum over the point's rays b. The points are taken by track length k (the structure's
:attr:`~orientviz.bundle.reduced.ReducedStructure.tracks`): for each ray b one product
of the k blocks Q_cc(i_a, i_b) stacked (kd × d) with T_b, then the sums over b for all
points of a chunk at once (:func:`segment_sum`). Without a border the point cofactors
and the rays' blocks follow chunk by chunk in the same pass (:func:`ray_cofactors`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ._store import LAYOUT_FREE_TERMS, ray_blocks

F64 = NDArray[np.float64]

#: Up to this many doubles the blocks of Q_cc are laid out for every ordered image pair
#: (m² d² doubles, 16 MB): a pair's block is then found by i·m + k, without a search.
FULL_PAIRS_DOUBLES: int = 2**21

#: Doubles of the gathered blocks per chunk of points in :func:`cofactors_by_pairs`
#: (1 MB: the gather and its products stay in the processor's cache).
PAIR_CHUNK_DOUBLES: int = 2**17

#: numpy's pairwise summation: blocks of this many elements are summed by 8 accumulators
#: (``PW_BLOCKSIZE`` in numpy's ``loops_utils.h.src``).
PAIRWISE_BLOCK: int = 128


def _pairwise(X: F64, lo: int, n: int) -> F64:
    """Σ X[:, lo : lo + n] over axis 1, added in the order of numpy's pairwise summation
    (a new array; n ≥ 1)."""
    if n < 8:  # one accumulator (numpy starts from −0.0: −0.0 + x is x)
        out = X[:, lo].copy()
        for i in range(lo + 1, lo + n):
            out += X[:, i]
        return out
    if n <= PAIRWISE_BLOCK:  # eight accumulators, their tree, then the rest in turn
        r = [X[:, lo + j].copy() for j in range(8)]
        end = n - n % 8
        for i in range(8, end, 8):
            for j in range(8):
                r[j] += X[:, lo + i + j]
        out = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
        for i in range(end, n):
            out += X[:, lo + i]
        return out
    n2 = n // 2
    n2 -= n2 % 8
    return _pairwise(X, lo, n2) + _pairwise(X, lo + n2, n - n2)


def segment_sum(X: F64) -> F64:
    """Σ over axis 1 of X (rows, k, …) as ``np.add.reduceat`` sums a segment of k
    elements along its axis: the first plus the pairwise sum of the others
    (:func:`_pairwise`), each addition an array operation over all rows. The same
    additions in the same order, so the same numbers to the last bit, as
    ``np.add.reduceat(X.reshape(-1, …), starts, axis=0)`` with segments of k."""
    k = X.shape[1]
    if k == 1:
        return X[:, 0].copy()
    return X[:, 0] + _pairwise(X, 1, k - 1)


def _ordered_blocks(S, Zblk: F64):
    """The blocks of Z at ordered image pairs (i, k): ``(Zs, index)``, ``Zs[index(i, k)]``
    = Z(i, k): the stored block (i ≤ k) or the transpose of block (k, i) (a pair i = k
    takes its block as stored). Laid out for all m² pairs when that is small
    (:data:`FULL_PAIRS_DOUBLES`), else the blocks and their transposes side by side,
    found by a search in the structure's sorted keys."""
    m, nb, d = S.n_cam, Zblk.shape[0], Zblk.shape[1]
    Zboth = np.concatenate([Zblk, Zblk.transpose(0, 2, 1)])
    if m * m * d * d <= FULL_PAIRS_DOUBLES:
        at = np.zeros((m, m), np.int64)
        at[S.block_k, S.block_i] = nb + np.arange(nb)  # the transposes first: (i, i) stays
        at[S.block_i, S.block_k] = np.arange(nb)
        return np.take(Zboth, at.reshape(-1), axis=0), lambda i, k: i * m + k
    keys = S.block_i * m + S.block_k

    def index(i, k):
        return np.searchsorted(keys, np.minimum(i, k) * m + np.maximum(i, k)) + (i > k) * nb

    return Zboth, index


def _chunks(S, d: int):
    """The points by track length in chunks of at most :data:`PAIR_CHUNK_DOUBLES` gathered
    block entries: ``(k, rays, first point, points)`` (``rays`` a slice in the bundle's
    track order)."""
    tg = S.tracks
    p0 = 0
    for k, r0, n in tg.groups:
        step = max(1, PAIR_CHUNK_DOUBLES // (d * d * k * k))
        for c0 in range(0, n, step):
            c1 = min(c0 + step, n)
            a, b = r0 + k * c0, r0 + k * c1
            yield k, (slice(a, b) if tg.in_order else tg.rays[a:b]), p0 + c0, c1 - c0
        p0 += n


def _pair_products(S, Zs, index, T: F64, k: int, rays) -> F64:
    """Q_cp = −Σ_b Q(i_a, i_b) T_b of the rays of one chunk of points with k rays each
    (:func:`cofactors_by_pairs`), shape (rays, d, 3)."""
    d = T.shape[1]
    img = S.obs_cam[rays].reshape(-1, k)
    Zg = np.take(Zs, index(img[:, None, :], img[:, :, None]), axis=0)  # (points, b, a, d, d)
    QT = np.matmul(Zg.reshape(-1, k * d, d), T[rays])  # (points · b, a · d, 3)
    return -segment_sum(QT.reshape(-1, k, k, d, 3)).reshape(-1, d, 3)


def cofactors_by_pairs(S, Zblk: F64, T: F64, Qcp: F64) -> None:
    """Q_cp of each ray of a point unknown into ``Qcp`` (n, d, 3): −Σ_b Q(i_a, i_b) T_b
    over the rays b of its point.

    Parameters
    ----------
    S : orientviz.bundle.reduced.ReducedStructure
        The structure (its blocks and :attr:`tracks`).
    Zblk : ndarray, shape (n_blocks, d, d)
        Q_cc at the structure's blocks (i ≤ k); d = 6, or 6 + k with the cameras in the
        images' blocks.
    T : ndarray, shape (n, d, 3)
        T = W V⁻¹ per observation.
    Qcp : ndarray, shape (n, d, 3)
        Written at the rays of point unknowns.

    Notes
    -----
    Per chunk of points of one track length k: the blocks of every pair gathered as
    (points, b, a) — for each ray b its k blocks Q(i_a, i_b) one (kd × d) matrix — times
    T_b (one product per ray b, each entry the same d-term product as a (d × d)(d × 3)
    product per pair), then summed over b by :func:`segment_sum` in the order of a
    reduction per ray a: the numbers of a product per pair of rays summed by
    ``np.add.reduceat``.
    """
    d = Zblk.shape[1]
    Zs, index = _ordered_blocks(S, Zblk)
    for k, rays, _, _ in _chunks(S, d):
        Qcp[rays] = _pair_products(S, Zs, index, T, k, rays)


def ray_cofactors(
    S, Zblk: F64, T: F64, Vinv: F64, Qimg: F64, img, Jc: F64, Jp: F64, dQcp=None, dQpp=None
):
    """Q_pp and the rays' gains and 2 × 2 blocks, chunk by chunk of points:
    :func:`cofactors_by_pairs`, :func:`point_cofactors` and
    :func:`orientviz.bundle.precision._store.ray_blocks` in one pass (Q_cp of a chunk is
    used while it is in the cache and never stored whole; every entry the same
    operations in the same order as theirs).

    Parameters
    ----------
    S, Zblk, T : as :func:`cofactors_by_pairs`.
    Vinv : ndarray, shape (p_var, 3, 3)
        Inverse point blocks.
    Qimg : ndarray, shape (m, d, d)
        Q_cc of each image.
    img : ndarray of int, shape (n,)
        Each ray's image.
    Jc, Jp : ndarray, shapes (n, 2, d), (n, 2, 3)
        Weighted designs of the rays by their image's unknowns and by their point.
    dQcp, dQpp : ndarray, shapes (n, d, 3), (p_var, 3, 3), optional
        A border's terms, subtracted from Q_cp of each ray and from Q_pp of each point
        before the rays' blocks are formed (the parameters' terms of
        :func:`orientviz.bundle.precision._precision_ap.point_terms`).

    Returns
    -------
    Qpp : ndarray, shape (p_var, 3, 3)
    Kc, Kp, H : ndarray, shapes (n, d, 2), (n, 3, 2), (n, 2, 2)
        As :func:`~orientviz.bundle.precision._store.ray_blocks` (``Kp`` zero for rays of
        fixed points).
    """
    d = Zblk.shape[1]
    tg = S.tracks
    Zs, index = _ordered_blocks(S, Zblk)
    n_rays = Jc.shape[0]
    Kc, Kp, H = np.empty((n_rays, d, 2)), np.zeros((n_rays, 3, 2)), np.empty((n_rays, 2, 2))
    Qpp = np.empty_like(Vinv)
    # the transposed designs once for all chunks, where ray_blocks reads them contiguous
    JcT = np.ascontiguousarray(Jc.transpose(0, 2, 1)) if d < LAYOUT_FREE_TERMS else None
    JpT = np.ascontiguousarray(Jp.transpose(0, 2, 1))
    for k, rays, p0, n in _chunks(S, d):
        Qc = _pair_products(S, Zs, index, T, k, rays)
        if dQcp is not None:
            Qc -= dQcp[rays]
        P = T[rays].transpose(0, 2, 1) @ (-Qc)  # (n k, 3, 3)
        pts = tg.points[p0 : p0 + n]
        Qp = np.take(Vinv, pts, axis=0) + segment_sum(P.reshape(n, k, 3, 3))
        if dQpp is not None:
            Qp -= dQpp[pts]
        Qpp[pts] = Qp
        each = np.repeat(np.arange(n), k)  # each ray's point in the chunk
        args = (Qimg, img[rays], Qc, Qp, Jc[rays], Jp[rays], slice(None), each)
        args += (None if JcT is None else JcT[rays], JpT[rays])
        if tg.in_order:  # written in place (views)
            ray_blocks(*args, out=(Kc[rays], Kp[rays], H[rays]))
        else:
            Kc[rays], Kp[rays], H[rays] = ray_blocks(*args)
    fixed = np.flatnonzero(S.obs_pt < 0)  # rays of fixed points: their image's term only
    if fixed.size:
        Kc[fixed] = Qimg[img[fixed]] @ Jc[fixed].transpose(0, 2, 1)
        H[fixed] = Jc[fixed] @ Kc[fixed]
    return Qpp, Kc, Kp, H


def point_cofactors(Vinv: F64, T: F64, Qcp: F64, S) -> F64:
    """Q_pp,j = V_j⁻¹ − Σ_b T_bᵀ Q_cp(i_b, j) over the rays b of each point unknown j,
    shape (p_var, 3, 3): per track group one product per ray and the sums over each
    point's rays as ``np.add.reduceat`` adds them (:func:`segment_sum`)."""
    tg = S.tracks
    out = np.empty_like(Vinv)
    p0 = 0
    for k, r0, n in tg.groups:
        rays = slice(r0, r0 + n * k) if tg.in_order else tg.rays[r0 : r0 + n * k]
        P = T[rays].transpose(0, 2, 1) @ (-Qcp[rays])  # (n k, 3, 3)
        pts = tg.points[p0 : p0 + n]
        out[pts] = Vinv[pts] + segment_sum(P.reshape(n, k, 3, 3))
        p0 += n
    return out


def var_rows(obs) -> slice | NDArray[np.int64]:
    """The rays of point unknowns (``obs.column`` ≥ 0; −1: a fixed point) in the rays'
    own order: a slice when they come first (the bundle's track order), else their
    indices."""
    var = obs.column >= 0
    nv = int(np.count_nonzero(var))
    return slice(0, nv) if bool(var[:nv].all()) else np.flatnonzero(var)
