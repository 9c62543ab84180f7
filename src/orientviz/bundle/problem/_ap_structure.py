"""The index orders of the additional parameters' border terms (constant over the iterations).

:class:`APStructure` holds, for a bundle with self-calibration parameters in G groups (see
:mod:`._ap_normal`), the *(point, group)* pairs of the rays, the sparse 0/1 matrices that sum
per-ray or per-pair products by pair, image and group, the scatter matrix of H = Σ Aᵀ P J_p
and the direct term Σ Aᵀ P A per group (:meth:`APStructure.refresh`: a camera model's design
changes at every linearisation), and, formed on first use, the pair lists of the other
groups' terms and the point batches (:mod:`._ap_batches`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..reduced._structure import stable_order
from ._ap_batches import PointBatch, point_batches

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


def _summation(keys: I64) -> tuple[sp.csr_matrix, I64]:
    """Sparse 0/1 matrix that sums the rows with equal key, and the sorted distinct keys.

    ``M @ X`` (X of len(keys) rows) adds up the rows of every key — a segment sum that
    SciPy's sparse product does faster than ``np.add.reduceat`` or ``np.add.at``.
    """
    uk, inv = np.unique(keys, return_inverse=True)
    M = sp.csr_matrix(
        (np.ones(keys.size), (inv.ravel(), np.arange(keys.size))), shape=(uk.size, keys.size)
    )
    return M, uk


#: Up to this many coupled group pairs (g1, g2) the F term is one product per pair
#: (fast for a few aerial groups); beyond, stacked per-point products.
GROUP_PAIR_LOOP_MAX: int = 64


class APStructure:
    """Index orders for the additional-parameter terms (constant over the iterations).

    Parameters
    ----------
    oi : ndarray of int, shape (n,)
        Image of each used observation.
    ocol : ndarray of int, shape (n,)
        Point unknown of each observation (−1 for fixed points).
    pt_obs : ndarray of int
        Observations of point unknowns, sorted by point (``ReducedStructure.pt_obs``).
    n_pt : int
        Number of point unknowns (each has at least one observation).
    grp : ndarray of int, shape (m,)
        Group of each image.
    G : int
        Number of groups.
    Aw : ndarray, shape (n, 2, k)
        Design matrix of the parameters, weighted (rows · 1/σ).
    """

    def __init__(
        self, oi: I64, ocol: I64, pt_obs: I64, n_pt: int, grp: I64, G: int, Aw: F64
    ) -> None:
        self.G = G
        n = oi.size
        go = grp[oi]
        # observations by group (direct F and ba terms)
        self.grp_present = np.flatnonzero(np.bincount(go, minlength=G))  # = np.unique(go)
        # the direct F term Σ Aᵀ P A: one product per group over its rays (:meth:`refresh`)
        if G == 1:  # the rays are in group order (None)
            self._by_group, self._group_bounds = None, np.array([0, n])
        else:
            by_group = np.argsort(go, kind="stable")
            self._group_bounds = np.searchsorted(go[by_group], self.grp_present.tolist() + [G])
            in_order = np.array_equal(by_group, np.arange(n))
            self._by_group = None if in_order else by_group

        # (point, group) pairs: rays of one point in images of one group
        vo = pt_obs
        pgkey = ocol[vo] * G + go[vo]
        if G == 1:  # a pair per point (every point unknown has rays): its own index
            uk, inv = np.arange(n_pt), pgkey
        else:
            uk, inv = np.unique(pgkey, return_inverse=True)
            inv = inv.ravel()
        k = Aw.shape[2]
        self.pg_pt, self.pg_grp = uk // G, uk % G
        npg = uk.size
        # point → its range of (point, group) pairs (pairs are sorted by point)
        first = np.searchsorted(self.pg_pt, np.arange(n_pt))
        count = np.diff(np.r_[first, npg])
        self.sum_pt = sp.csr_matrix((np.ones(npg), (self.pg_pt, np.arange(npg))), shape=(n_pt, npg))
        # per image, its rays side by side (padded with a zero ray n): the image's own
        # group's E block is then one small matrix product per image (BLAS)
        m = grp.size
        cnt = np.bincount(oi, minlength=m)
        order = stable_order(oi, m)
        self._pad: tuple | None = None  # (pad, pad0): formed on first use (the precision)
        # the rays image by image in the same order, unpadded, and where each image's
        # rows (2 per ray) begin and end: the own group's E block as one product per image
        # over its own rays (:func:`ap_normal`)
        self.by_image = order
        self.image_rows = 2 * np.r_[0, np.cumsum(cnt)]
        # (point, group) pair of each ray's own group (npg: none, fixed point)
        self.own_pg = np.full(n, npg, np.int64)
        self.own_pg[vo] = inv  # the index of each ray's pair key in uk
        # H = Σ Aᵀ P J_p per pair as one sparse product with the (2n, 3) weighted point
        # Jacobian: Mᵀ (2n, npg·k) holds in row 2·ray + coordinate the ray's weighted
        # design at the columns of its own pair (k per row: CSR formed directly); M = Mᵀ.T
        # is then a CSC matrix, whose product scatters each ray into its pair
        var = self.own_pg < npg
        nvar = int(var.sum())
        it = np.int32 if max(2 * nvar * k, npg * k) < 2**31 else np.int64
        cols = self.own_pg[var].astype(it)[:, None, None] * it(k) + np.arange(k, dtype=it)
        indptr = np.zeros(2 * n + 1, it)
        np.cumsum(np.repeat(np.where(var, k, 0).astype(it), 2), out=indptr[1:])
        self._var = None if nvar == n else var  # None: every ray
        self._h_index = (np.broadcast_to(cols, (nvar, 2, k)).reshape(-1), indptr)
        self._h_shape = (2 * n, npg * k)
        self.H_design: sp.csc_matrix | None = None
        self.refresh(Aw)
        # E correction in the *other* groups of a ray's point (rays of points in the
        # overlap of two groups): its blocks (image, group) = the pattern of (image ×
        # point) · (point × group) without each image's own group
        if G == 1:  # one group: no other group's blocks, one coupled group pair
            self.e_key = np.zeros(0, np.int64)
            n_coupled = int(npg > 0)
        else:
            inc_img = sp.csr_matrix((np.ones(vo.size), (oi[vo], ocol[vo])), shape=(m, n_pt))
            inc_grp = sp.csr_matrix((np.ones(npg), (self.pg_pt, self.pg_grp)), shape=(n_pt, G))
            reach = (inc_img @ inc_grp).tocoo()
            key = reach.row.astype(np.int64) * G + reach.col
            self.e_key = np.unique(key[reach.col != grp[reach.row]])
            # the coupled group pairs (g1, g2): two groups that share a point
            n_coupled = (inc_grp.T @ inc_grp).nnz
        # block sums of E @ v and Eᵀ @ y: other blocks → their image, images and other
        # blocks → their group
        K, ki, gi = self.e_key.size, self.e_key // G, self.e_key % G
        self.sum_other_img = sp.csr_matrix((np.ones(K), (ki, np.arange(K))), shape=(m, K))
        self.sum_other_grp = sp.csr_matrix((np.ones(K), (gi, np.arange(K))), shape=(G, K))
        self.sum_img_grp = sp.csr_matrix((np.ones(m), (grp, np.arange(m))), shape=(G, m))
        # (point, group) pairs by group (ba correction); observations by point
        self.sum_pgg, self.pgg_present = _summation(self.pg_grp)
        self._lists = (oi, go, vo, ocol, first, count)
        self._pairs: dict[str, NDArray] | None = None
        self._sum_e: sp.csr_matrix | None = None
        # many coupled group pairs (a group per image: BAL, per-image COLMAP cameras): the
        # E and F terms by stacked per-point products (:mod:`._ap_batches`); a few
        # (aerial groups): one product per group pair and per-ray products, over the
        # lists of :meth:`_pair_lists` (formed on first use, as for the precision)
        # (the batches are formed on first use: a problem evaluated without its normal
        # equations, e.g. the viewer opening a model at its start values, needs none)
        self._k = k
        self._batches: list[PointBatch] | None = None
        self.batched = n_coupled > GROUP_PAIR_LOOP_MAX
        self.sum_img: sp.csr_matrix | None = None  # sums per-ray terms by image (E's own blocks)
        if self.batched:
            self.sum_img = sp.csr_matrix((np.ones(n), (oi, np.arange(n))), shape=(m, n))

    @property
    def batches(self) -> list[PointBatch] | None:
        """The point batches of the E and F terms (:mod:`._ap_batches`), formed on first
        use; None when there are few coupled group pairs (per group pair instead)."""
        if self.batched and self._batches is None:
            oi, go, vo, ocol, first, count = self._lists
            self._batches = point_batches(oi, go, vo, ocol, first, count, self, self._k)
        return self._batches if self.batched else None

    @batches.setter
    def batches(self, value: list[PointBatch] | None) -> None:
        self._batches, self.batched = value, value is not None

    def _pair_lists(self) -> dict[str, NDArray]:
        """Every (ray, pair of another group of its point) and every ordered pair of
        (point, group) pairs of one point, sorted by their groups (formed on first use:
        millions of entries for a model of long tracks and a group per image)."""
        if self._pairs is not None:
            return self._pairs
        oi, go, vo, ocol, first, count = self._lists
        G = self.G
        a = vo
        ca = count[ocol[a]]
        e_obs = np.repeat(a, ca)
        off = np.arange(e_obs.size) - np.repeat(np.cumsum(ca) - ca, ca)
        e_pg = np.repeat(first[ocol[a]], ca) + off
        other = self.pg_grp[e_pg] != go[e_obs]
        e_obs, e_pg = e_obs[other], e_pg[other]
        c1 = count[self.pg_pt]
        f1 = np.repeat(np.arange(self.pg_pt.size), c1)
        off = np.arange(f1.size) - np.repeat(np.cumsum(c1) - c1, c1)
        f2 = np.repeat(first[self.pg_pt], c1) + off
        # F's correction is one product per (g1, g2) over its pairs (g1 = g2: the pairs of
        # one group with themselves)
        fkey = self.pg_grp[f1] * G + self.pg_grp[f2]
        o = np.argsort(fkey, kind="stable")
        f_key, first_f = np.unique(fkey[o], return_index=True)
        self._pairs = dict(
            e_obs=e_obs, e_pg=e_pg, e_rows=oi[e_obs] * G + self.pg_grp[e_pg],
            f_1=f1[o], f_2=f2[o], f_key=f_key, f_bounds=np.r_[first_f, o.size],
        )  # fmt: skip
        return self._pairs

    @property
    def e_obs(self) -> I64:
        """The rays of the (ray, other-group pair) products (:meth:`_pair_lists`)."""
        return self._pair_lists()["e_obs"]

    @property
    def e_pg(self) -> I64:
        """The pairs of the (ray, other-group pair) products (:meth:`_pair_lists`)."""
        return self._pair_lists()["e_pg"]

    @property
    def _e_rows(self) -> I64:
        return self._pair_lists()["e_rows"]

    @property
    def f_1(self) -> I64:
        """First pairs of the ordered pairs of one point's pairs (:meth:`_pair_lists`)."""
        return self._pair_lists()["f_1"]

    @property
    def f_2(self) -> I64:
        """Second pairs of the ordered pairs of one point's pairs (:meth:`_pair_lists`)."""
        return self._pair_lists()["f_2"]

    @property
    def f_key(self) -> I64:
        """The group pairs g1 · G + g2 of ``f_1``, ``f_2`` (sorted, distinct)."""
        return self._pair_lists()["f_key"]

    @property
    def f_bounds(self) -> I64:
        """Where each group pair's entries of ``f_1``, ``f_2`` begin (and the end)."""
        return self._pair_lists()["f_bounds"]

    @property
    def sum_e(self) -> sp.csr_matrix:
        """Sums the (ray, other pair) products into E's other-group blocks (``e_key``);
        formed on first use."""
        if self._sum_e is None:
            self._sum_e, _ = _summation(self._e_rows)
        return self._sum_e

    def refresh(self, Aw: F64) -> None:
        """Set the terms that depend on the design's values (Σ Aᵀ P A per group, the
        scatter matrix of H) for a new weighted design ``Aw`` (n, 2, k) on the same rays.

        Linear sets call it once; a model whose design changes with the iterate
        (:class:`orientviz.bundle.LensModel`) at every linearisation.
        """
        order, bounds = self._by_group, self._group_bounds
        # the rays by group (no copy when they are in that order already: one group)
        Ao = (Aw if order is None else Aw[order]).reshape(-1, Aw.shape[2])
        self.F_direct = np.stack(
            [Ao[2 * a : 2 * b].T @ Ao[2 * a : 2 * b] for a, b in zip(bounds[:-1], bounds[1:])]
        )
        # (every ray: a view of the design, which is never changed in place)
        data = (Aw if self._var is None else Aw[self._var]).reshape(-1)
        if self.H_design is None:
            Mt = sp.csr_matrix((data, *self._h_index), shape=self._h_shape)
            self.H_design = Mt.T
        else:  # the same pattern: its values replaced
            self.H_design.data = data

    @property
    def pad(self) -> I64:
        """(m, L) each image's rays side by side, padded with the zero ray n (formed on
        first use)."""
        return self._padded()[0]

    @property
    def pad0(self) -> I64:
        """:attr:`pad` with the padding slots pointing at ray 0 instead: a gather of a
        per-ray array through it needs no appended zero row, where the partner (the
        reduced design, gathered through ``pad``) is zero for padded slots."""
        return self._padded()[1]

    @property
    def L(self) -> int:
        """The largest number of rays of an image (:attr:`pad`'s width)."""
        return self._padded()[0].shape[1]

    def _padded(self) -> tuple:
        if self._pad is None:
            oi, order, n = self._lists[0], self.by_image, self._h_shape[0] // 2
            cnt = np.diff(self.image_rows) // 2
            pos = np.arange(n) - np.repeat(np.cumsum(cnt) - cnt, cnt)
            pad = np.full((cnt.size, max(int(cnt.max(initial=0)), 1)), n, np.int64)
            pad[oi[order], pos] = order
            self._pad = (pad, np.where(pad < n, pad, 0))
        return self._pad
