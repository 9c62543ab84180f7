"""Multifrontal Cholesky of the reduced camera system S along a nested dissection.

S (n = 6m unknowns, 6 × 6 blocks) is factored node by node of its dissection tree
(:mod:`orientviz.bundle.reduced._dissection`), children before parents. A node with ``p``
pivot unknowns and ``b`` boundary unknowns owns a dense *front* ::

    F = [F11  F21ᵀ]   p     F11 = RᵀR (R upper triangular, LAPACK potrf),
        [F21  F22 ]   b     L21ᵀ = R⁻ᵀ F21ᵀ,  update F22 − L21 L21ᵀ (syrk)

assembled from S's blocks of its pivot images and the *updates* F22 of its children
(each added at the rows of its boundary in this front: *extend-add*). All dense work is
LAPACK/BLAS through SciPy (``dpotrf``, ``dtrtri``, ``dtrmm``, ``dsyrk``), in place on
Fortran-ordered views:

* the factor of a node is stored as one (p × (p + b)) array ``[R⁻¹ | L21ᵀ]`` in one
  buffer for all nodes (R⁻¹ instead of R: the updates use ``dtrmm`` instead of
  ``dtrsm``, and the solves multiply instead of substitute);
* the updates F22 (upper triangles) live in a work arena kept by the layout and reused
  by every factorisation, at offsets fixed once (first fit among the updates alive);
* a child's boundary is a few runs of consecutive rows of its parent, so an extend-add
  is a few 2-D slice additions, not an index scatter.

The layout (:class:`FrontLayout`) is built once per structure; :func:`factor_fronts`
fills a new buffer per factorisation (its arena is the layout's: one factorisation of a
structure at a time), :func:`solve_fronts` solves with it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import blas, lapack

from ._dissection import Dissection

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]
_R6 = np.arange(6)


@dataclass
class FrontLayout:
    """Where every front, update and entry of S lives (constant over the iterations).

    Attributes
    ----------
    p, b : ndarray of int
        Pivot and boundary unknowns of each node (postorder).
    factor_at, update_at : ndarray of int
        Offset of each node's factor ``[R⁻¹ | L21ᵀ]`` in the factor buffer and of its
        update (b × b) in the arena.
    first : ndarray of int
        First unknown (elimination order) of each node's pivots.
    rows_below : list of ndarray of int
        Unknowns (elimination order) of each node's boundary.
    to_factor, to_update : list of list of tuple
        Per node the extend-add of its children: (child, child rows, front rows) as
        slices ``(c0, c1, f0)`` of runs, pairs of runs going to the factor part (the
        front's pivot columns) and to the update part.
    entry_at, entry_of : ndarray of int
        Positions in the factor buffer of the entries of S's blocks taken in the order
        ``entry_of`` (blocks sorted by where they go: near-sequential writes; in S's
        order the scatter over the whole buffer misses the caches).
    scalar_perm : ndarray of int, shape (n,)
        Unknown of S at each position of the elimination order.
    size, arena_size : int
        Doubles of a factor buffer and of the arena.
    """

    p: I64
    b: I64
    factor_at: I64
    update_at: I64
    first: I64
    rows_below: list
    to_factor: list
    to_update: list
    entry_at: I64
    entry_of: I64
    scalar_perm: I64
    size: int
    arena_size: int
    arena: F64 | None = field(default=None, repr=False)

    @property
    def n_nodes(self) -> int:
        return self.p.size


def _scalars(images: I64) -> I64:
    return (6 * np.asarray(images, np.int64)[:, None] + _R6).reshape(-1)


def front_layout(diss: Dissection, block_i: I64, block_k: I64) -> FrontLayout:
    """The :class:`FrontLayout` of a dissection for S's blocks (i ≤ k)."""
    pos = diss.pos
    m, nn = pos.size, diss.n_nodes
    npiv = np.array([v.size for v in diss.pivots], np.int64)
    nbd = np.array([v.size for v in diss.boundary], np.int64)
    p, b = 6 * npiv, 6 * nbd
    factor_at = np.concatenate([[0], np.cumsum(p * (p + b))]).astype(np.int64)
    first_img = np.concatenate([[0], np.cumsum(npiv)[:-1]])  # position of a node's first pivot
    node_of = np.repeat(np.arange(nn), npiv)  # node of each position
    # a front's rows: its pivots, then its boundary (positions, sorted); the row of a
    # later image in node j's front by one search in the boundaries of all nodes
    bd_pos = [pos[v] for v in diss.boundary]
    bd_keys = np.concatenate([j * m + v for j, v in enumerate(bd_pos)] + [np.zeros(0, np.int64)])
    bd_start = np.concatenate([[0], np.cumsum(nbd)[:-1]])

    def row_in(j: I64, q: I64) -> I64:
        """Row (image units) of position q in the front of node j."""
        own = q < first_img[j] + npiv[j]
        below = np.searchsorted(bd_keys, j * m + q) - bd_start[j] + npiv[j]
        return np.where(own, q - first_img[j], below)

    kids: list = [[] for _ in range(nn)]
    for j, q in enumerate(diss.parent.tolist()):
        if q >= 0:
            kids[q].append(j)
    update_at, top = _arena(b, kids)
    # extend-add: each child's boundary as runs of consecutive rows of its parent
    to_factor: list = [[] for _ in range(nn)]
    to_update: list = [[] for _ in range(nn)]
    child = np.flatnonzero((diss.parent >= 0) & (nbd > 0))
    if child.size:
        cimg = np.concatenate([bd_pos[c] for c in child])
        cof = np.repeat(child, nbd[child])
        par = diss.parent[cof]
        rel = row_in(par, cimg)
        # runs: consecutive rows, cut where a child's list starts or the pivots end
        new = np.ones(rel.size, bool)
        new[1:] = (np.diff(rel) != 1) | (cof[1:] != cof[:-1]) | (rel[1:] == npiv[par[1:]])
        starts = np.flatnonzero(new)
        ends = np.append(starts[1:], rel.size)
        offset = np.repeat(np.cumsum(nbd[child]) - nbd[child], nbd[child])
        runs_of: dict = {}
        for s0, e0 in zip(starts.tolist(), ends.tolist()):
            c = int(cof[s0])
            c0 = 6 * (s0 - int(offset[s0]))
            runs_of.setdefault(c, []).append((c0, c0 + 6 * (e0 - s0), 6 * int(rel[s0])))
        for c, runs in runs_of.items():
            j = int(diss.parent[c])
            for ia, ra in enumerate(runs):
                for rb in runs[: ia + 1]:  # row run ra at or below column run rb
                    (to_factor if rb[2] < p[j] else to_update)[j].append((c, rb, ra))
    # S's entries: block (i, k) goes to the node of whichever image is eliminated first;
    # entry (r, c) is S[6i + r, 6k + c]: row (row image, r or c) of column (column
    # image, c or r) of that front, stored at [column, row]
    col_first = pos[block_i] <= pos[block_k]
    col_pos = pos[np.where(col_first, block_i, block_k)]
    row_pos = pos[np.where(col_first, block_k, block_i)]
    j = node_of[col_pos]
    base = factor_at[j] + 6 * row_in(j, row_pos) * p[j] + 6 * (col_pos - first_img[j])
    r6, c6 = _R6[:, None], _R6[None, :]
    local = np.where(
        col_first[:, None, None], (c6 * p[j][:, None, None] + r6), (r6 * p[j][:, None, None] + c6)
    )
    order = np.argsort(base, kind="stable")  # blocks in buffer order: near-sequential writes
    entry_at = (base[:, None, None] + local)[order].reshape(-1)
    scalar_perm = _scalars(diss.perm)
    return FrontLayout(
        p, b, factor_at, update_at, 6 * first_img, [_scalars(v) for v in bd_pos], to_factor,
        to_update, entry_at, order, scalar_perm, int(factor_at[-1]), top,
    )  # fmt: skip


def _arena(b: I64, kids: list) -> tuple[I64, int]:
    """Offsets of the updates (b × b) in the arena: an update lives from its node's
    syrk to its parent's extend-add; first fit among those alive."""
    update_at = np.zeros(b.size, np.int64)
    live: list = []  # (start, end, node)
    top = 0
    for j in range(b.size):
        need = int(b[j] * b[j])
        at = 0
        for s, e, _ in sorted(live):
            if at + need <= s:
                break
            at = max(at, e)
        update_at[j] = at
        top = max(top, at + need)
        dead = set(kids[j])
        live = [t for t in live if t[2] not in dead] + ([(at, at + need, j)] if need else [])
    return update_at, top


class NotPositiveDefinite(np.linalg.LinAlgError):
    """A front's pivot block is not positive definite; ``unknown``: the unknown of S
    (original numbering) at which the elimination broke down."""

    def __init__(self, unknown: int) -> None:
        super().__init__(f"not positive definite at unknown {unknown}")
        self.unknown = unknown


def factor_fronts(lay: FrontLayout, blocks: F64) -> F64:
    """Factor S given its 6 × 6 blocks (i ≤ k): the factor buffer (:class:`FrontLayout`).

    Raises :class:`NotPositiveDefinite` at the first non-positive pivot.
    """
    L = np.zeros(lay.size)
    L[lay.entry_at] = np.take(blocks, lay.entry_of, axis=0).reshape(-1)
    if lay.arena is None or lay.arena.size < lay.arena_size:
        # zeros: the lower triangles are never written by syrk, only added to (ignored)
        lay.arena = np.zeros(max(lay.arena_size, 1))
    arena = lay.arena
    for j in range(lay.n_nodes):
        p, b = int(lay.p[j]), int(lay.b[j])
        o = int(lay.factor_at[j])
        U = L[o : o + p * (p + b)].reshape((p, p + b), order="F")
        for c, (c0, c1, f0), (a0, a1, g0) in lay.to_factor[j]:
            C = _update(lay, arena, c)
            U[f0 : f0 + c1 - c0, g0 : g0 + a1 - a0] += C[c0:c1, a0:a1]
        R = U[:, :p]
        _, info = lapack.dpotrf(R, lower=0, overwrite_a=1, clean=0)
        if info > 0:
            raise NotPositiveDefinite(int(lay.scalar_perm[lay.first[j] + info - 1]))
        if info < 0 or not np.isfinite(R[:: p + 1]).all():
            raise NotPositiveDefinite(int(lay.scalar_perm[lay.first[j]]))
        _, info = lapack.dtrtri(R, lower=0, overwrite_c=1)
        if info:  # pragma: no cover - a successful potrf has a non-zero diagonal
            raise NotPositiveDefinite(int(lay.scalar_perm[lay.first[j] + max(info, 1) - 1]))
        if not b:
            continue
        X = blas.dtrmm(1.0, R, U[:, p:], side=0, lower=0, trans_a=1, overwrite_b=1)
        if not np.shares_memory(X, U):  # pragma: no cover - views are contiguous
            U[:, p:] = X
        F22 = _update(lay, arena, j)
        blas.dsyrk(-1.0, X, beta=0.0, c=F22, trans=1, lower=0, overwrite_c=1)
        for c, (c0, c1, f0), (a0, a1, g0) in lay.to_update[j]:
            C = _update(lay, arena, c)
            F22[f0 - p : f0 - p + c1 - c0, g0 - p : g0 - p + a1 - a0] += C[c0:c1, a0:a1]
    return L


def _update(lay: FrontLayout, arena: F64, j: int) -> F64:
    """Node j's update (b × b, upper triangle) in the arena, Fortran order."""
    b = int(lay.b[j])
    o = int(lay.update_at[j])
    return arena[o : o + b * b].reshape((b, b), order="F")


def solve_fronts(lay: FrontLayout, L: F64, rhs: F64) -> F64:
    """Solve S x = rhs, rhs of shape (n,) or (n, k), with the factor buffer ``L``."""
    one = rhs.ndim == 1
    x = rhs[lay.scalar_perm].reshape(rhs.shape[0], -1)
    x = np.asfortranarray(x)
    fronts = []
    for j in range(lay.n_nodes):
        p, b = int(lay.p[j]), int(lay.b[j])
        o = int(lay.factor_at[j])
        fronts.append(L[o : o + p * (p + b)].reshape((p, p + b), order="F"))
    for j, U in enumerate(fronts):  # forward: y = R⁻ᵀ x_p, x_b −= L21 y
        p, f = int(lay.p[j]), int(lay.first[j])
        y = blas.dtrmm(1.0, U[:, :p], x[f : f + p], side=0, lower=0, trans_a=1)
        x[f : f + p] = y
        if lay.b[j]:
            rb = lay.rows_below[j]
            x[rb] -= U[:, p:].T @ y
    for j in range(lay.n_nodes - 1, -1, -1):  # backward: x_p = R⁻¹ (y − L21ᵀ x_b)
        U = fronts[j]
        p, f = int(lay.p[j]), int(lay.first[j])
        y = x[f : f + p]
        if lay.b[j]:
            y = y - U[:, p:] @ x[lay.rows_below[j]]
        x[f : f + p] = blas.dtrmm(1.0, U[:, :p], y, side=0, lower=0)
    out = np.empty_like(x)
    out[lay.scalar_perm] = x
    return out[:, 0] if one else out
