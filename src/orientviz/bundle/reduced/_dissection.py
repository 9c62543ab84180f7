"""Nested dissection of the image graph: the elimination tree of a sparse Cholesky of S.

The reduced camera system S (6 × 6 blocks, one block row per image; see
:mod:`orientviz.bundle.reduced`) has a block (i, k) wherever images i and k share a
point: its *image graph*. A Cholesky factor of S fills in between images that are
connected through images eliminated before them. *Nested dissection* bounds that fill:
a small set of images (a *separator*) whose removal splits the graph into two parts is
numbered last, the two parts first, each dissected again the same way, down to parts
of at most ``leaf`` images (:attr:`ReducedOptions.leaf_images
<orientviz.bundle.reduced.ReducedOptions>`). The parts never couple each other, so their
eliminations only update the separators above them.

Every node of the resulting tree (a separator, or a leaf part) is eliminated as one
dense *front* (:mod:`orientviz.bundle.reduced._multifrontal`): its own ``p`` unknowns and the
``b`` unknowns of the images of separators above it that it touches (its *boundary*),
at ≈ p³/3 + p²b + pb² flops (:attr:`Dissection.flops`).

A bisection's separator is

* *geometric* (with projection centres): the images are split at the median of their
  centres along the longer principal horizontal axis; the separator is the images of
  one half that touch the other half (the smaller of the two such sets). On a block of
  strips this cuts across the strips (two columns of images: an image shares points
  with the images two along its strip) or between two strips. All parts of one level
  of the tree are cut in one vectorised pass over the edges.
* *level structure* (graph only, when there are no centres): breadth-first levels
  from a pseudo-peripheral image; any level separates the levels before it from those
  after it; the smallest level leaving at least ``balance`` of the images on each
  side, without its images that touch only one side (part by part: slower).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse import csgraph

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


@dataclass
class Dissection:
    """The elimination tree of nested dissection, nodes in postorder.

    Attributes
    ----------
    pivots : list of ndarray of int
        Images eliminated at each node (a separator or a leaf part), in elimination order.
    boundary : list of ndarray of int
        Images of later nodes (ancestors' separators) coupled to the node's subtree, in
        elimination order: the rows of the node's front below its pivots.
    parent : ndarray of int
        Parent node of each node (−1 for a root: one per connected part).
    perm, pos : ndarray of int, shape (m,)
        Images in elimination order, and the position of each image in it.
    """

    pivots: list
    boundary: list
    parent: I64
    perm: I64
    pos: I64

    @property
    def flops(self) -> float:
        """Flops of the dense fronts (6 unknowns per image): Σ p³/3 + p²b + pb²."""
        p = 6.0 * np.array([v.size for v in self.pivots])
        b = 6.0 * np.array([v.size for v in self.boundary])
        return float(np.sum(p**3 / 3 + p * p * b + p * b * b))

    @property
    def n_nodes(self) -> int:
        return len(self.pivots)


def image_adjacency(block_i: I64, block_k: I64, m: int) -> sp.csr_matrix:
    """Symmetric adjacency (m × m, no diagonal) of images sharing a point."""
    off = block_i != block_k
    i, k = block_i[off], block_k[off]
    return sp.csr_matrix(
        (np.ones(2 * i.size, np.int8), (np.concatenate([i, k]), np.concatenate([k, i]))),
        shape=(m, m),
    )


def _touching(sub: sp.csr_matrix, side: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """Vertices with a neighbour in ``side`` (boolean mask over the sub-graph)."""
    return (sub @ side.astype(np.int8)) > 0


def _geometric_cut(sub: sp.csr_matrix, xy: F64):
    """(A, B, separator) masks: a median cut of the centres along their longer axis."""
    c = xy - xy.mean(axis=0)
    _, _, vt = np.linalg.svd(c, full_matrices=False)
    order = np.argsort(c @ vt[0], kind="stable")
    left = np.zeros(len(xy), bool)
    left[order[: len(xy) // 2]] = True
    s_right = ~left & _touching(sub, left)
    s_left = left & _touching(sub, ~left)
    if s_right.sum() <= s_left.sum():
        return left, ~left & ~s_right, s_right
    return left & ~s_left, ~left, s_left


def _level_cut(sub: sp.csr_matrix, balance: float = 0.3):
    """(A, B, separator) masks from a breadth-first level structure, or None."""
    n = sub.shape[0]
    start, ecc, d = 0, -1.0, None
    for _ in range(4):  # pseudo-peripheral start: the far end of a far end
        d = csgraph.shortest_path(sub, unweighted=True, indices=start, directed=False)
        if not np.isfinite(d).all():
            return None
        if d.max() <= ecc:
            break
        ecc = d.max()
        far = np.flatnonzero(d == ecc)
        start = int(far[np.argmin(np.diff(sub.indptr)[far])])
    levels = d.astype(np.int64)
    cnt = np.bincount(levels)
    before = np.cumsum(cnt) - cnt
    after = n - before - cnt
    ok = (np.minimum(before, after) >= balance * n) & (np.arange(cnt.size) > 0)
    if not ok.any():
        return None
    lv = int(np.flatnonzero(ok)[np.argmin(cnt[ok])])
    a, b, s = levels < lv, levels > lv, levels == lv
    move = s & ~_touching(sub, b)  # separator images that touch only A
    a, s = a | move, s & ~move
    move = s & ~_touching(sub, a)
    return a, b | move, s & ~move


def nested_dissection(
    block_i: I64,
    block_k: I64,
    m: int,
    positions: F64 | None = None,
    leaf: int = 12,
    merge: int = 0,
    balance: float = 0.3,
) -> Dissection:
    """The :class:`Dissection` of the image graph given by the blocks of S.

    Parameters
    ----------
    block_i, block_k : ndarray of int
        Images of the blocks (i ≤ k) of S (:func:`orientviz.bundle.reduced._choice.image_blocks`).
    m : int
        Number of images.
    positions : ndarray, shape (m, 3), optional
        Projection centres (m): geometric separators (all parts of a level at once,
        vectorised); without them, level-structure separators (part by part).
    leaf : int
        Parts of at most this many images are leaves.
    merge : int
        Separators of at most this many images join their parent's (0: none).
    balance : float
        A level-structure separator leaves at least this fraction of a part on each side.
    """
    off = block_i != block_k
    eu = np.concatenate([block_i[off], block_k[off]])
    ev = np.concatenate([block_k[off], block_i[off]])
    if positions is not None:
        xy = np.asarray(positions, float)[:, :2]
        pivots, parent = _build_geometric(eu, ev, xy, m, leaf)
    else:
        adj = image_adjacency(block_i, block_k, m)
        pivots, parent = _build(adj, leaf, balance)
    pivots, parent = _postorder(pivots, parent)
    if merge:
        pivots, parent = _postorder(*_merge_small(pivots, parent, merge))
    perm = np.concatenate(pivots).astype(np.int64) if pivots else np.zeros(0, np.int64)
    pos = np.empty(m, np.int64)
    pos[perm] = np.arange(m)
    pivots = [np.sort(pos[v]) for v in pivots]  # as positions from here on
    boundary = _boundaries(pos[eu], pos[ev], pivots, parent)
    return Dissection([perm[v] for v in pivots], [perm[v] for v in boundary], parent, perm, pos)


def _merge_small(pivots: list, parent: I64, limit: int) -> tuple[list, I64]:
    """Separators of at most ``limit`` images joined to their parent's separator (nodes in
    postorder): fewer, larger fronts — a small front's update is a low-rank product that
    writes as many entries as a large one."""
    piv = list(pivots)
    par = parent.copy()
    alive = np.ones(len(piv), bool)
    has_kids = np.zeros(len(piv), bool)
    has_kids[par[par >= 0]] = True
    for j in range(len(piv)):
        q = par[j]
        if q < 0 or not has_kids[j] or piv[j].size > limit:
            continue
        piv[q] = np.concatenate([piv[q], piv[j]])
        par[par == j] = q
        alive[j] = False
    keep = np.flatnonzero(alive)
    new = np.full(len(piv), -1, np.int64)
    new[keep] = np.arange(keep.size)
    return [piv[j] for j in keep], np.where(par[keep] >= 0, new[np.maximum(par[keep], 0)], -1)


def _postorder(pivots: list, parent: I64) -> tuple[list, I64]:
    """The nodes renumbered in postorder (children before parents, subtrees contiguous)."""
    n = len(pivots)
    kids: list = [[] for _ in range(n)]
    roots = []
    for j, q in enumerate(parent.tolist()):
        (kids[q] if q >= 0 else roots).append(j)
    order: list = []
    stack = [(r, False) for r in reversed(roots)]
    while stack:
        j, done = stack.pop()
        if done:
            order.append(j)
            continue
        stack.append((j, True))
        stack.extend((c, False) for c in reversed(kids[j]))
    new = np.empty(n, np.int64)
    new[order] = np.arange(n)
    par = np.array([new[parent[j]] if parent[j] >= 0 else -1 for j in order], np.int64)
    return [pivots[j] for j in order], par


def _build_geometric(eu: I64, ev: I64, xy: F64, m: int, leaf: int) -> tuple[list, I64]:
    """Nodes (pivot images) and parents of the geometric dissection, level by level: every
    part larger than ``leaf`` is cut at the median of its centres along its longer
    principal axis, all parts of a level in one pass over the edges."""
    part = np.zeros(m, np.int64)  # current part of each image (−1: in a separator)
    part_parent = [-1]  # node above each part
    pivots: list = []
    parent: list = []
    while True:
        live = part >= 0
        size = np.bincount(part[live], minlength=len(part_parent))
        big = size > leaf
        done = live & ~big[np.maximum(part, 0)]
        for q in np.unique(part[done]).tolist():  # leaves
            pivots.append(np.flatnonzero(part == q))
            parent.append(part_parent[q])
        part[done] = -1
        act = np.flatnonzero(part >= 0)
        if not act.size:
            break
        q, x, y = part[act], xy[act, 0], xy[act, 1]
        nq = len(part_parent)
        cnt = np.bincount(q, minlength=nq).astype(float)
        cnt[cnt == 0] = 1.0
        mx, my = np.bincount(q, x, nq) / cnt, np.bincount(q, y, nq) / cnt
        dx, dy = x - mx[q], y - my[q]
        sxx, syy = np.bincount(q, dx * dx, nq), np.bincount(q, dy * dy, nq)
        sxy = np.bincount(q, dx * dy, nq)
        ang = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)  # the longer principal axis
        t = dx * np.cos(ang[q]) + dy * np.sin(ang[q])
        o = np.lexsort((t, q))
        start = np.searchsorted(q[o], np.arange(nq))
        rank = np.empty(act.size, np.int64)
        rank[o] = np.arange(act.size) - start[q[o]]
        left = np.zeros(m, bool)
        left[act] = rank < size[q] // 2
        # edges inside one active part crossing the cut: their right and left ends
        same = (part[eu] == part[ev]) & (part[eu] >= 0)
        cross = same & left[eu] & ~left[ev]
        s_right = np.zeros(m, bool)
        s_right[ev[cross]] = True
        s_left = np.zeros(m, bool)
        s_left[eu[cross]] = True
        n_r = np.bincount(part[s_right], minlength=nq)
        n_l = np.bincount(part[s_left], minlength=nq)
        use_r = n_r <= n_l  # per part: the smaller one-sided separator
        sep = np.where(use_r[part], s_right, s_left) & (part >= 0)
        new_part = part.copy()
        for p_ in np.unique(q).tolist():
            members = sep & (part == p_)
            above = part_parent[p_]
            if members.any():
                pivots.append(np.flatnonzero(members))
                parent.append(above)
                above = len(pivots) - 1
            a_id, b_id = len(part_parent), len(part_parent) + 1
            part_parent.extend([above, above])
            in_p = part == p_
            new_part[in_p & left & ~sep] = a_id
            new_part[in_p & ~left & ~sep] = b_id
        new_part[sep] = -1
        part = new_part
    return pivots, np.asarray(parent, np.int64)


def _build(adj: sp.csr_matrix, leaf: int, balance: float = 0.3) -> tuple[list, I64]:
    """Nodes (pivot images, postorder) and parents by level-structure bisection."""
    pivots: list = []
    parent: list = []

    def rec(verts: I64) -> list:
        """Emit the subtree of ``verts``; returns the indices of its roots."""
        sub = adj[verts][:, verts] if verts.size > leaf else None
        cut = _level_cut(sub, balance) if sub is not None else None
        if cut is None:  # a leaf, or no balanced separator (e.g. a clique): one front
            pivots.append(verts)
            parent.append(-1)
            return [len(pivots) - 1]
        a, b, s = cut
        roots = (rec(verts[a]) if a.any() else []) + (rec(verts[b]) if b.any() else [])
        if not s.any():  # independent parts: no node of their own
            return roots
        pivots.append(verts[s])
        parent.append(-1)
        me = len(pivots) - 1
        for r in roots:
            parent[r] = me
        return [me]

    ncomp, lab = csgraph.connected_components(adj, directed=False)
    order = np.argsort(lab, kind="stable")
    starts = np.searchsorted(lab[order], np.arange(ncomp + 1))
    for c in range(ncomp):
        rec(order[starts[c] : starts[c + 1]])
    return pivots, np.asarray(parent, np.int64)


def _boundaries(pu: I64, pv: I64, pivots: list, parent: I64) -> list:
    """Per node the positions (sorted) of later images coupled to its subtree: an edge
    (lo, hi) of positions lo < hi belongs to the node of lo and every ancestor of it
    eliminated before hi."""
    nn = len(pivots)
    m = int(sum(v.size for v in pivots))
    node_of = np.empty(m, np.int64)
    last = np.empty(nn, np.int64)
    for j, v in enumerate(pivots):
        node_of[v] = j
        last[j] = v[-1]
    up = pu < pv
    lo, hi = pu[up], pv[up]
    node = node_of[lo]
    keys = []
    while node.size:
        keep = last[node] < hi
        node, hi = node[keep], hi[keep]
        keys.append(node * m + hi)
        node = parent[node]
        keep = node >= 0
        node, hi = node[keep], hi[keep]
    k = np.unique(np.concatenate(keys)) if keys else np.zeros(0, np.int64)
    cut = np.searchsorted(k // m, np.arange(nn + 1))
    return [k[cut[j] : cut[j + 1]] % m for j in range(nn)]


def check_dissection(diss: Dissection, block_i: I64, block_k: I64) -> None:
    """Raise ``AssertionError`` unless every separator separates: an image couples only to
    images of its own subtree or of the boundary of its node (the property the fronts
    rely on)."""
    m = diss.pos.size
    node_of = np.empty(m, np.int64)
    for j, v in enumerate(diss.pivots):
        node_of[v] = j
    for a, b in zip(block_i.tolist(), block_k.tolist()):
        if a == b:
            continue
        lo, hi = (a, b) if diss.pos[a] < diss.pos[b] else (b, a)
        j = node_of[lo]
        rows = np.concatenate([diss.pivots[j], diss.boundary[j]])
        assert hi in set(rows.tolist()), f"images {lo} and {hi} couple across a separator"
