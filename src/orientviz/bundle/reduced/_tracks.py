"""The Schur complement of a sparse block by points grouped by their track length.

S = U − Σ_j W_j V_j⁻¹ W_jᵀ gains, for a point j seen in k images, the k × k blocks of
T_j W_jᵀ (T_j = W_j V_j⁻¹ and W_j stacked: 6k × 3). The points are grouped by k: the
(6k × 6k) products of all points of a group are one batched product (``np.matmul`` on a
stack), and their sum into the blocks of S is one product with a constant sparse matrix
that maps each 6-element row of a product to its row of a block of S, with the sign of
the subtraction. The per-ray arrays of
:meth:`orientviz.bundle.problem.BundleProblem.normal` are formed in this ray order; its sums per
point and per image are products with constant sparse incidence matrices.

:class:`TrackGroups` holds the constant layout (formed once per problem).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: Largest product array (doubles) of one batched call; bigger groups are split.
CHUNK_DOUBLES: int = 2**20
#: Largest product array (doubles) of one batched call of :func:`schur_blocks` with more
#: than the 6 exterior unknowns per image (:meth:`TrackGroups.chunks`).
BLOCK_CHUNK_DOUBLES: int = 2**18


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
    points : ndarray of int, shape (p_var,)
        Point unknown of each point in this order (its first ray: ``rays[first]``).
    groups : list of (k, first ray, number of points)
        The groups (chunks of at most :data:`CHUNK_DOUBLES` product entries).
    in_order : bool
        ``rays`` is 0, 1, …, n_var − 1: the observations are in this order (the bundle's
        are, :func:`orientviz.bundle.problem._parts.image_observations`), per-ray arrays are
        slices of the observations' arrays.
    work : dict
        Work arrays of a formation in this ray order kept from one iteration to the next
        (arrays of a few MB formed anew in every iteration cost their page faults again;
        :mod:`orientviz.bundle.problem._camera_blocks`); released with the maps.
    n_images, n_points : int
        m and p_var.

    Properties :attr:`by_image` and :attr:`by_point` (the (m, n_var) and (p_var, n_var)
    incidences of image and ray, point and ray: sums per image and per point by one
    sparse product) are formed when first read.
    """

    rays: I64
    ray_point: I64
    ray_image: I64
    points: I64
    groups: list
    in_order: bool = False
    n_images: int = 0
    n_points: int = 0
    _maps: dict = field(default_factory=dict, repr=False)
    work: dict = field(default_factory=dict, repr=False)
    _incidence: dict = field(default_factory=dict, repr=False)

    @property
    def by_image(self) -> sp.csr_matrix:
        """(m, n_var) incidence of image and ray (formed on first read)."""
        return self._incidences("image", self.ray_image, self.n_images)

    @property
    def by_point(self) -> sp.csr_matrix:
        """(p_var, n_var) incidence of point and ray (formed on first read)."""
        return self._incidences("point", self.ray_point, self.n_points)

    def _incidences(self, name: str, of_ray: I64, rows: int) -> sp.csr_matrix:
        M = self._incidence.get(name)
        if M is None:
            ones, ray = np.ones(self.rays.size), np.arange(self.rays.size)
            M = sp.csr_matrix((ones, (of_ray, ray)), shape=(rows, self.rays.size))
            self._incidence[name] = M
        return M

    @property
    def rows(self) -> slice | I64:
        """The observations of the rays in this order (a slice when ``in_order``)."""
        return slice(0, self.rays.size) if self.in_order else self.rays

    def take(self, a: F64) -> F64:
        """The rows of ``a`` (per observation) of the rays in this order."""
        return a[: self.rays.size] if self.in_order else np.take(a, self.rays, axis=0)

    def chunks(self, d: int = 6) -> list:
        """The groups as :func:`schur_blocks` forms them with d unknowns per image:
        ``groups`` for d = 6; for other d split into chunks of whole points whose products
        hold at most :data:`BLOCK_CHUNK_DOUBLES` entries (a smaller work space)."""
        if d == 6:
            return self.groups
        out = []
        for k, r0, n in self.groups:
            step = max(1, BLOCK_CHUNK_DOUBLES // (d * d * k * k))
            out += [(k, r0 + k * c0, min(step, n - c0)) for c0 in range(0, n, step)]
        return out

    def maps(self, keys: I64, m: int, d: int = 6) -> list:
        """Per group a CSC matrix (d · n_blocks, n_points · dk · k): −1 where row r of the
        product block (a, b) of a point (image(a) ≤ image(b)) adds into row r of S's
        block (image(a), image(b)); ``keys`` = block_i · m + block_k of S's blocks
        (sorted); ``d`` unknowns per image (6: the exterior orientation). Formed on first
        use per ``d`` (one d-element row per pair of rays: Σ k(k+1)/2 · d entries)."""
        if d not in self._maps:
            lookup = _block_lookup(keys, m)
            minus = _MinusOnes()  # the maps' values, one array shared by them
            maps = []
            for k, r0, n in self.chunks(d):
                img = self.ray_image[r0 : r0 + n * k].reshape(n, k)
                ascending = k > 1 and bool(np.all(img[:, 1:] > img[:, :-1]))
                build = _ascending_group_map if ascending else _group_map
                maps.append(build(img, lookup, keys.size, d, minus))
            self._maps[d] = maps
        return self._maps[d]


def _block_lookup(keys: I64, m: int):
    """A function (i, k) → index of block (i, k), i ≤ k, in ``keys`` (= i·m + k, sorted):
    a dense table (m × span) when the blocks lie within a span of image numbers (strips
    numbered along the strips: a few hundred), else a binary search."""
    i, k = keys // m, keys % m
    span = int(np.max(k - i, initial=0)) + 1
    if m * span > 2**24:
        return lambda a, b: np.searchsorted(keys, a * m + b)
    table = np.zeros((m, span), np.int32)
    table[i, k - i] = np.arange(keys.size, dtype=np.int32)
    return lambda a, b: table[a, b - a]


class _MinusOnes:
    """Views of one array of −1.0 (grown when asked for more): the maps' values, shared
    instead of an array of −1 per map (the sparse products read them only; scipy copies
    a view given to its constructor, so the maps take theirs after it)."""

    def __init__(self) -> None:
        self.a = np.zeros(0)

    def __call__(self, size: int) -> F64:
        if size > self.a.size:
            self.a = np.full(max(size, 2 * self.a.size), -1.0)
        return self.a[:size]


def _csc(rows, indptr, shape: tuple[int, int], minus) -> sp.csc_matrix:
    """The CSC matrix of −1 values at ``rows`` with column pointers ``indptr``: its
    values a view of the shared −1s (``minus``: :class:`_MinusOnes`; None: its own)."""
    if minus is None or max(shape) >= 2**31:  # (the constructor picks the index type)
        M = sp.csc_matrix((np.full(rows.size, -1.0), rows, indptr), shape=shape)
        if minus is not None:
            M.data = minus(rows.size)
        return M
    # formed empty and given its arrays (the constructor would copy a view of the
    # shared values: an array of −1 per map again)
    M = sp.csc_matrix(shape)
    M.indices, M.indptr, M.data = rows, indptr, minus(rows.size)
    return M


def _group_map(img: I64, lookup, n_blocks: int, d: int = 6, minus=None) -> sp.csc_matrix:
    """The map of one group (n points × k images, ``img``) into the rows of S's blocks
    (``lookup``: :func:`_block_lookup`) of d × d."""
    n, k = img.shape
    # pairs (n, a, b) of rays of a point with image(a) ≤ image(b), and their blocks
    keep = img[:, :, None] <= img[:, None, :]
    blk = np.zeros((n, k, k), np.int32)
    ia, ib = np.broadcast_arrays(img[:, :, None], img[:, None, :])
    blk[keep] = lookup(ia[keep], ib[keep])
    # the product's rows (n, a, r, b) of the (n, dk, dk) products viewed as (·, d): one
    # CSC column each, holding the row r of block blk[n, a, b] where kept
    keep6 = np.broadcast_to(keep[:, :, None, :], (n, k, d, k)).reshape(-1)
    rows6 = d * blk[:, :, None, :] + np.arange(d, dtype=np.int32)[None, None, :, None]
    rows = rows6.reshape(-1)[keep6]
    indptr = np.zeros(keep6.size + 1, np.int32)
    np.cumsum(keep6, out=indptr[1:])
    return _csc(rows, indptr, (d * n_blocks, keep6.size), minus)


@lru_cache(maxsize=64)
def _point_pattern(k: int, d: int) -> tuple:
    """One point's pattern of :func:`_ascending_group_map` for k rays and d unknowns per
    image: the pairs (iu, ju) of rays a ≤ b, and of its (dk × dk) product's rows (a, r,
    b), row-major, the kept ones' pair and row r within the block, and the kept rows
    before each row. Read only (shared by the maps of every group of k rays)."""
    iu, ju = np.triu_indices(k)
    a, r, b = (x.reshape(-1) for x in np.indices((k, d, k)))
    kept = a <= b
    pair = np.zeros((k, k), np.int64)
    pair[iu, ju] = np.arange(iu.size)
    sel, r_kept = pair[a[kept], b[kept]], r[kept].astype(np.int32)
    before = (np.cumsum(kept) - kept).astype(np.int32)
    out = (iu, ju, sel, r_kept, before)
    for x in out:
        x.flags.writeable = False
    return out


def _ascending_group_map(img: I64, lookup, n_blocks: int, d: int = 6, minus=None) -> sp.csc_matrix:
    """:func:`_group_map` for points whose rays are in ascending image order (as the
    bundle's set-up orders them): the kept pairs are a ≤ b for every point, so the map
    is one point's pattern (:func:`_point_pattern`) repeated (no masks over all n·dk²
    product rows; the same matrix)."""
    n, k = img.shape
    iu, ju, sel, r_kept, before = _point_pattern(k, d)
    blk = lookup(img[:, iu], img[:, ju])  # (n, pairs)
    rows = blk[:, sel].astype(np.int32, copy=False)
    rows *= np.int32(d)
    rows += r_kept
    per_point, width = sel.size, before.size
    indptr = np.empty(n * width + 1, np.int32)
    np.add(
        per_point * np.arange(n, dtype=np.int32)[:, None],
        before,
        out=indptr[:-1].reshape(n, width),
    )
    indptr[-1] = n * per_point
    return _csc(rows.reshape(-1), indptr, (d * n_blocks, n * width), minus)


def track_groups(st) -> TrackGroups:
    """The :class:`TrackGroups` of a :class:`~orientviz.bundle.reduced.ReducedStructure`."""
    m = st.n_cam
    k_pt = np.diff(np.append(st.pt_starts, st.pt_obs.size))
    order = np.argsort(k_pt, kind="stable")  # points by track length
    k_sorted = k_pt[order]
    rays_all, groups = [], []
    n0 = 0
    for k in np.unique(k_pt).tolist():
        pts_k = order[np.searchsorted(k_sorted, k) : np.searchsorted(k_sorted, k, "right")]
        step = max(1, CHUNK_DOUBLES // (36 * k * k))
        for c0 in range(0, pts_k.size, step):
            pts = pts_k[c0 : c0 + step]
            rays_all.append(st.pt_obs[(st.pt_starts[pts][:, None] + np.arange(k)).reshape(-1)])
            groups.append((k, n0, pts.size))
            n0 += rays_all[-1].size
    rays = np.concatenate(rays_all) if rays_all else np.zeros(0, np.int64)
    ray_point, ray_image = st.obs_pt[rays], st.obs_cam[rays]
    first = [r0 + k * np.arange(n) for k, r0, n in groups]  # first ray of each point
    points = ray_point[np.concatenate(first)] if groups else rays
    in_order = bool(np.array_equal(rays, np.arange(rays.size)))
    return TrackGroups(rays, ray_point, ray_image, points, groups, in_order, m, st.n_pt)


#: Rays per chunk of :func:`point_products` (its temporaries stay in the cache).
RAY_CHUNK: int = 8192


#: Tracks up to this length are summed by k − 1 array additions (the same sums in the
#: same order as a reduction over the short middle axis, without its overhead).
SUM_BY_ADDS_MAX_K: int = 16


def _sum_rays(X: F64) -> F64:
    """Σ over axis 1 of (points, k, ...): the k rays of each point."""
    k = X.shape[1]
    if k > SUM_BY_ADDS_MAX_K or k < 2:
        return X.sum(axis=1)
    out = X[:, 0] + X[:, 1]
    for j in range(2, k):
        out += X[:, j]
    return out


def point_products(tg: TrackGroups, Jew: F64, Jpw: F64, rw: F64, n_pt: int, out: F64 | None = None):
    """W = J_eᵀ P J_p per ray and the point blocks V = Σ J_pᵀ P J_p, b_p = Σ J_pᵀ P (l − f).

    Parameters
    ----------
    tg : TrackGroups
    Jew, Jpw : ndarray, shapes (n, 2, d), (n, 2, 3)
        Weighted Jacobians (P½ J) of all observations: by the d unknowns of the ray's
        image (the exterior orientation X0, Y0, Z0, ω, φ, κ first, then any of its
        camera's), by the point.
    rw : ndarray, shape (n, 2)
        Weighted misclosures P½ (l − f).
    n_pt : int
        Number of point unknowns.
    out : ndarray, shape (n_var, d, 3), optional
        Where W is written (default: a new array).

    Returns
    -------
    Wr : ndarray, shape (n_var, d, 3)
        In ``tg.rays`` order.
    V, bp : ndarray, shapes (p_var, 3, 3), (p_var, 3)
        In point-unknown order.

    Chunks of :data:`RAY_CHUNK` rays of whole points: the rays of a point are
    consecutive, so their sums are reshapes, and the temporaries stay small (large
    fresh temporaries cost their page faults; a stacked product runs faster on a
    contiguous copy of a transpose than on the view). V is summed from W's upper 3 × 3 blocks
    (−J_pᵀ P J_p: the derivatives by X0 are those by X negated), not formed again.
    """
    nv = tg.rays.size
    Wr = np.empty((nv, Jew.shape[2], 3)) if out is None else out
    V = np.empty((n_pt, 3, 3))
    bp = np.empty((n_pt, 3))
    p0 = 0  # points done
    for k, r0, n in tg.groups:
        step = max(1, RAY_CHUNK // k)
        for c0 in range(0, n, step):
            c1 = min(c0 + step, n)
            a, b = r0 + k * c0, r0 + k * c1
            if tg.in_order:  # the rays are these observations: views
                Jer, Jpr, rwr = Jew[a:b], Jpw[a:b], rw[a:b]
            else:
                rr = tg.rays[a:b]
                Jer, Jpr, rwr = (np.take(x, rr, axis=0) for x in (Jew, Jpw, rw))
            np.matmul(np.ascontiguousarray(Jer.transpose(0, 2, 1)), Jpr, out=Wr[a:b])
            pts = tg.points[p0 + c0 : p0 + c1]
            # ∂/∂X0 = −∂/∂X (f depends on X − X0): W's upper 3 × 3 block is −J_pᵀ P J_p
            V[pts] = -_sum_rays(Wr[a:b, :3].reshape(c1 - c0, k, 3, 3))
            g = Jpr[:, 0, :] * rwr[:, 0, None] + Jpr[:, 1, :] * rwr[:, 1, None]
            bp[pts] = _sum_rays(g.reshape(c1 - c0, k, 3))
        p0 += n
    return Wr, V, bp


def ray_couplings(tg: TrackGroups, W: F64, Vinv: F64, out: F64 | None = None) -> F64:
    """T = W V⁻¹ per ray (n_var, d, 3) in ``tg.rays`` order, from W (same order) and the
    point blocks' inverses V⁻¹ (p_var, 3, 3): per point one (dk × 3)(3 × 3) product of
    its k rays stacked (no per-ray gather of V⁻¹; the same sums as per ray). ``out``: where T
    is written (default: a new array)."""
    T = np.empty_like(W) if out is None else out
    d = W.shape[1]
    p0 = 0
    for k, r0, n in tg.groups:
        r1 = r0 + n * k
        Vk = np.take(Vinv, tg.points[p0 : p0 + n], axis=0)
        np.matmul(W[r0:r1].reshape(n, d * k, 3), Vk, out=T[r0:r1].reshape(n, d * k, 3))
        p0 += n
    return T


def point_sums_wt(tg: TrackGroups, W: F64, dc: F64) -> F64:
    """Σ over each point's rays of W_rayᵀ dc_image (p_var, 3), W (n_var, d, 3) in
    ``tg.rays`` order, dc (m, d) per image: per point one (1 × dk)(dk × 3) product."""
    out = np.empty((tg.points.size, 3))
    d = W.shape[1]
    p0 = 0
    for k, r0, n in tg.groups:
        r1 = r0 + n * k
        g = np.take(dc, tg.ray_image[r0:r1], axis=0).reshape(n, 1, d * k)
        out[tg.points[p0 : p0 + n]] = (g @ W[r0:r1].reshape(n, d * k, 3))[:, 0, :]
        p0 += n
    return out


def schur_buffer_size(tg: TrackGroups, d: int = 6) -> int:
    """Doubles of the work space of :func:`schur_blocks` for d unknowns per image."""
    return max((d * d * k * k * n for k, _, n in tg.chunks(d)), default=0)


def schur_blocks(st, U: F64, T: F64, W: F64, buf: F64 | None = None) -> F64:
    """The blocks (i ≤ k) of S = U − Σ_j T_j W_jᵀ from per-ray T, W in track order.

    Parameters
    ----------
    st : orientviz.bundle.reduced.ReducedStructure
        The structure (its blocks and :attr:`~ReducedStructure.tracks`).
    U : ndarray, shape (m, d, d)
        Image blocks (d = 6: the exterior orientation; more: an image's own camera too).
    T, W : ndarray, shape (n_var, d, 3)
        W V⁻¹ and W per ray, in ``st.tracks.rays`` order.
    buf : ndarray, optional
        Work space for the products, at least :func:`schur_buffer_size` doubles (default:
        a new array).

    Returns
    -------
    ndarray, shape (n_blocks, d, d)
        In the order of ``st.block_i``, ``st.block_k``.
    """
    tg = st.tracks
    d = U.shape[1]
    maps = tg.maps(st.block_i * st.n_cam + st.block_k, st.n_cam, d)
    out = np.zeros((d * st.n_blocks, d))
    # one buffer for the products of every chunk: reused memory (no fresh pages per call)
    if buf is None:
        buf = np.empty(schur_buffer_size(tg, d))
    for (k, r0, n), M in zip(tg.chunks(d), maps):
        r1 = r0 + n * k
        Tk = T[r0:r1].reshape(n, d * k, 3)
        Wk = W[r0:r1].reshape(n, d * k, 3)
        P = buf[: d * d * k * k * n].reshape(n, d * k, d * k)
        np.matmul(Tk, Wk.transpose(0, 2, 1), out=P)  # all k² blocks of each point
        out += M @ P.reshape(-1, d)
    blocks = out.reshape(st.n_blocks, d, d)
    blocks[st.diag_block] += U
    return blocks


def back_substitute(
    tg: TrackGroups, Vinv: F64, W: F64, bp: F64, dc: F64, border: F64 | None = None
) -> F64:
    """The point corrections dp_j = V_j⁻¹ (b_p,j − Σ_rays W_rayᵀ dc_image − t_j) (p_var, 3).

    Parameters
    ----------
    tg : TrackGroups
        The ray order of ``W``.
    Vinv : ndarray, shape (p_var, 3, 3)
        Inverse point blocks.
    W : ndarray, shape (n_var, d, 3)
        Per ray J_cᵀ P J_p, in ``tg.rays`` order.
    bp : ndarray, shape (p_var, 3)
        The points' right-hand sides.
    dc : ndarray, shape (m, d)
        The image corrections.
    border : ndarray, shape (p_var, 3), optional
        t_j, the term of a border's corrections (e.g. the additional parameters').
    """
    red = bp - point_sums_wt(tg, W, dc)
    if border is not None:
        red -= border
    return np.einsum("nij,nj->ni", Vinv, red)
