"""The Schur complement of a sparse block by points grouped by their track length.

S = U − Σ_j W_j V_j⁻¹ W_jᵀ gains, for a point j seen in k images, the k × k blocks of
T_j W_jᵀ (T_j = W_j V_j⁻¹ and W_j stacked: 6k × 3). Formed pair of rays by pair, this
is one tiny product and one reduction per pair (the code before session 6: ~60 ms on
the bench's 2 100-image block, 112 000 rays, 237 000 pairs). Here the points are grouped
by k: the (6k × 6k) products of all points of a group are one batched product
(``np.matmul`` on a stack), and their sum into the blocks of S is one product with a
constant sparse matrix that maps each 6-element row of a product to its row of a block
of S, with the sign of the subtraction (~15 ms). The per-ray arrays of
:meth:`orientviz.bundle.BundleProblem.normal` are formed in this ray order; its sums per
point and per image are products with constant sparse incidence matrices.

:class:`TrackGroups` holds the constant layout (formed once per problem).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: Largest product array (doubles) of one batched call; bigger groups are split.
CHUNK_DOUBLES: int = 2**20


@dataclass
class TrackGroups:
    """Rays of the point unknowns grouped by track length (constant over the iterations).

    Attributes
    ----------
    rays : ndarray of int, shape (n_var,)
        Observation index of every ray of a point unknown: group by group (k ascending),
        point by point, the k rays of a point consecutive.
    ray_point, ray_image : ndarray of int, shape (n_var,)
        Point unknown and image of each ray in ``rays``.
    groups : list of (k, first ray, number of points)
        The groups (chunks of at most :data:`CHUNK_DOUBLES` product entries).
    by_image, by_point : scipy.sparse.csr_matrix
        (m, n_var) and (p_var, n_var) incidences of image and ray, point and ray (sums
        per image and per point by one sparse product).
    """

    rays: I64
    ray_point: I64
    ray_image: I64
    groups: list
    by_image: sp.csr_matrix
    by_point: sp.csr_matrix
    _maps: list | None = field(default=None, repr=False)

    def maps(self, keys: I64, m: int) -> list:
        """Per group a CSC matrix (6 · n_blocks, n_points · 6k · k): −1 where row r of the
        product block (a, b) of a point (image(a) ≤ image(b)) adds into row r of S's
        block (image(a), image(b)); ``keys`` = block_i · m + block_k of S's blocks
        (sorted). Formed on first use (one 6-element row per pair of rays: Σ k(k+1)/2 · 6
        entries)."""
        if self._maps is None:
            self._maps = [
                _group_map(self.ray_image[r0 : r0 + n * k].reshape(n, k), keys, m)
                for k, r0, n in self.groups
            ]
        return self._maps


def _group_map(img: I64, keys: I64, m: int) -> sp.csc_matrix:
    """The map of one group (n points × k images, ``img``) into the rows of S's blocks."""
    n, k = img.shape
    # pairs (n, a, b) of rays of a point with image(a) ≤ image(b), and their blocks
    keep = img[:, :, None] <= img[:, None, :]
    blk = np.zeros((n, k, k), np.int32)
    ia, ib = np.broadcast_arrays(img[:, :, None], img[:, None, :])
    blk[keep] = np.searchsorted(keys, ia[keep] * m + ib[keep])
    # the product's rows (n, a, r, b) of the (n, 6k, 6k) products viewed as (·, 6): one
    # CSC column each, holding the row r of block blk[n, a, b] where kept
    keep6 = np.broadcast_to(keep[:, :, None, :], (n, k, 6, k)).reshape(-1)
    rows6 = 6 * blk[:, :, None, :] + np.arange(6, dtype=np.int32)[None, None, :, None]
    rows = rows6.reshape(-1)[keep6]
    indptr = np.zeros(keep6.size + 1, np.int32)
    np.cumsum(keep6, out=indptr[1:])
    return sp.csc_matrix(
        (np.full(rows.size, -1.0), rows, indptr), shape=(6 * keys.size, keep6.size)
    )


def track_groups(st) -> TrackGroups:
    """The :class:`TrackGroups` of a :class:`~orientviz.bundle._reduced.ReducedStructure`."""
    m = st.n_cam
    k_pt = np.diff(np.append(st.pt_starts, st.pt_obs.size))
    order = np.argsort(k_pt, kind="stable")  # points by track length
    rays_all, groups = [], []
    n0 = 0
    for k in np.unique(k_pt).tolist():
        pts_k = order[k_pt[order] == k]
        step = max(1, CHUNK_DOUBLES // (36 * k * k))
        for c0 in range(0, pts_k.size, step):
            pts = pts_k[c0 : c0 + step]
            rays_all.append(st.pt_obs[(st.pt_starts[pts][:, None] + np.arange(k)).reshape(-1)])
            groups.append((k, n0, pts.size))
            n0 += rays_all[-1].size
    rays = np.concatenate(rays_all) if rays_all else np.zeros(0, np.int64)
    ray_point, ray_image = st.obs_pt[rays], st.obs_cam[rays]
    ones, ray = np.ones(rays.size), np.arange(rays.size)
    by_image = sp.csr_matrix((ones, (ray_image, ray)), shape=(m, rays.size))
    by_point = sp.csr_matrix((ones, (ray_point, ray)), shape=(st.n_pt, rays.size))
    return TrackGroups(rays, ray_point, ray_image, groups, by_image, by_point)


def schur_blocks(st, U: F64, T: F64, W: F64) -> F64:
    """The blocks (i ≤ k) of S = U − Σ_j T_j W_jᵀ from per-ray T, W in track order.

    Parameters
    ----------
    st : orientviz.bundle._reduced.ReducedStructure
        The structure (its blocks and :attr:`~ReducedStructure.tracks`).
    U : ndarray, shape (m, 6, 6)
        Image blocks.
    T, W : ndarray, shape (n_var, 6, 3)
        W V⁻¹ and W per ray, in ``st.tracks.rays`` order.

    Returns
    -------
    ndarray, shape (n_blocks, 6, 6)
        In the order of ``st.block_i``, ``st.block_k``.
    """
    tg = st.tracks
    maps = tg.maps(st.block_i * st.n_cam + st.block_k, st.n_cam)
    out = np.zeros((6 * st.n_blocks, 6))
    # one buffer for the products of every chunk: reused memory (no fresh pages per call)
    buf = np.empty(max((36 * k * k * n for k, _, n in tg.groups), default=0))
    for (k, r0, n), M in zip(tg.groups, maps):
        r1 = r0 + n * k
        Tk = T[r0:r1].reshape(n, 6 * k, 3)
        Wk = W[r0:r1].reshape(n, 6 * k, 3)
        P = buf[: 36 * k * k * n].reshape(n, 6 * k, 6 * k)
        np.matmul(Tk, Wk.transpose(0, 2, 1), out=P)  # all k² blocks of each point
        out += M @ P.reshape(-1, 6)
    blocks = out.reshape(st.n_blocks, 6, 6)
    blocks[st.diag_block] += U
    return blocks
