"""Additional parameters in the bundle's normal equations: assembly and bordered solve.

With self-calibration the normal equations of the bundle (see
:mod:`orientviz.bundle.reduced`) gain a border of ``q = G·k`` group parameters ::

    [ S   E ] [dc]   [r ]      S  = reduced camera system (points eliminated)
    [ Eᵀ  F ] [da] = [ra]      E  = image × parameter coupling, F = parameter block

Both E and F carry, besides their direct terms (Jeᵀ P A, Aᵀ P A), the terms that the
elimination of the points leaves behind, ``−Σ_j W_j V_j⁻¹ H_jᵀ`` and ``−Σ_j H_j V_j⁻¹
H_jᵀ``. They are assembled here per *(point, group)* pair — all rays of a point that
lie in images of one group share the parameter columns, so their ``Aᵀ P J_p`` products
are summed first (``H``) — and with segment sums over index orders that are computed
once per problem (:class:`APStructure`) and applied as sparse 0/1 products; no
``np.add.at``.

How the border is then eliminated: :mod:`orientviz.bundle.problem._border`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..reduced import APBorder, ImageRays
from ..reduced._structure import stable_order
from ._ap_batches import PointBatch, batched_terms, point_batches

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


def _zero_row(X: F64) -> F64:
    """X with a row of zeros appended (the target of padding indices), in one pass."""
    out = np.empty((X.shape[0] + 1,) + X.shape[1:])
    out[:-1] = X
    out[-1] = 0.0
    return out


def _ssum(M: sp.csr_matrix, X: F64) -> F64:
    """Row sums by :func:`_summation` of X (N, a, b) → (K, a, b)."""
    return np.asarray(M @ X.reshape(X.shape[0], -1)).reshape((M.shape[0],) + X.shape[1:])


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


#: Up to this many coupled group pairs (g1, g2) the F term is one product per pair
#: (fast for a few aerial groups); beyond, stacked per-point products.
GROUP_PAIR_LOOP_MAX: int = 64


def _other_per_ray(A: APStructure, T: F64, H: F64, k: int) -> F64:
    """− Σ T_a H_eᵀ into E's other-group blocks (K, 6, k): one product per (ray, pair)."""
    if not A.e_key.size:
        return np.zeros((0, 6, k))
    return -_ssum(A.sum_e, T[A.e_obs] @ H[A.e_pg].transpose(0, 2, 1))


def _subtract_per_group_pair(A: APStructure, F4g: F64, VHt: F64, H: F64, k: int) -> None:
    """F4g (G², k, k) −= Σ H_e V⁻¹ H_e'ᵀ over the pairs (e, e') of one point: one product
    per (g1, g2), (V⁻¹ Hᵀ)ᵀ of e (3 × k) with Hᵀ of e' (3 × k) over all its pairs."""
    Htz = np.ascontiguousarray(H.transpose(0, 2, 1))
    for key, a, b in zip(A.f_key, A.f_bounds[:-1], A.f_bounds[1:]):
        F4g[key] -= VHt[A.f_1[a:b]].reshape(-1, k).T @ Htz[A.f_2[a:b]].reshape(-1, k)


def ap_normal(
    prob,
    st,
    rw: F64,
    Jew: F64,
    Jpw: F64,
    T: F64,
    Vinv: F64,
    bp: F64,
    lam: float,
    border: tuple[F64, F64] | None = None,
    rays: ImageRays | None = None,
) -> APBorder:
    """Border of the normal equations: E (6m, q), F (q, q), ba (q,) and helpers.

    Parameters
    ----------
    prob : BundleProblem
        With ``Aw`` (n, 2, k) weighted design, ``ap_struct`` (:class:`APStructure`).
    st : bundle state (``st.ap`` the current parameters).
    rw : ndarray, shape (n, 2)
        Weighted misclosures.
    Jew, Jpw : ndarray, shapes (n, 2, 6), (n, 2, 3)
        Weighted Jacobians.
    T : ndarray, shape (n, 6, 3)
        W_a V_j⁻¹ per observation (zero for fixed points).
    Vinv : ndarray, shape (p, 3, 3)
        Inverse point blocks.
    bp : ndarray, shape (p, 3)
        Point right-hand sides.
    lam : float
        Levenberg-Marquardt damping of the diagonal of F.
    border : (E, F0), optional
        E and the undamped F of an earlier iteration to use instead of forming them (the
        right-hand side ``ba`` and ``H`` are always of this iteration).
    rays : ImageRays, optional
        The rays sorted by image as the images' Gram matrices read them, P½J_e in their
        first 6 columns (then ``Jew`` is not read for the own-group blocks of E).

    Returns
    -------
    APBorder
        ``E_border`` (E by blocks), ``F`` (damped), ``F0`` (undamped), ``ba``, ``H`` (per
        (point, group) pair, k × 3: Σ Aᵀ P J_p over the pair's rays; for the
        back-substitution and the precision).
    """
    A, k, G, m = prob.ap.structure, prob.ap.k, prob.ap.G, prob.m
    # Aᵀ P (l − f) = Aᵀ (rw / σ): the unweighted design times the weighted misclosures
    ba2 = (prob.ap.A_csr.T @ (rw * prob.obs.weight).reshape(-1)).reshape(G, k)
    # point-elimination terms, per (point, group) pair: H = Σ Aᵀ P J_p over its rays
    H = (A.H_design @ Jpw.reshape(-1, 3)).reshape(-1, k, 3)  # (npg, k, 3)
    HV = H @ Vinv[A.pg_pt]  # H V⁻¹
    hb = (HV @ bp[A.pg_pt][:, :, None])[:, :, 0]
    ba2[A.pgg_present] -= A.sum_pgg @ hb
    ba = ba2.reshape(-1) - prob.ap.w * st.ap
    if border is not None:
        E, F0 = border
        return _damped(E, F0, ba, H, lam)
    # E: per image, its own group's block Σ_a (J_eᵀ P A − T Hᵀ) = Σ_a J_eᵀ P½ Ã with the
    # reduced design Ã = P½ (A − J_p V⁻¹ Hᵀ) of each ray (T = J_eᵀ P J_p V⁻¹, H of the
    # ray's own (point, group) pair)
    n = Jpw.shape[0]
    VHt = np.empty((H.shape[0] + 1, 3, k))  # V⁻¹ Hᵀ = (H V⁻¹)ᵀ (V⁻¹ symmetric), and a zero
    VHt[:-1] = HV.transpose(0, 2, 1)
    VHt[-1] = 0.0
    At = np.empty((n + 1, 2, k))  # the reduced design and a zero ray for the padding
    tg = prob.reduced.tracks
    if A.pg_pt.size == prob.points.n and tg.in_order:  # one pair per point (one group):
        # per point one (2k × 3)(3 × k) product of its k rays (the same sums as per ray,
        # without gathering V⁻¹Hᵀ per ray)
        p0 = 0
        for kk, r0, npt in tg.groups:
            r1 = r0 + npt * kk
            Vp = VHt[tg.points[p0 : p0 + npt]]
            np.matmul(Jpw[r0:r1].reshape(npt, 2 * kk, 3), Vp, out=At[r0:r1].reshape(npt, 2 * kk, k))
            p0 += npt
        At[tg.rays.size : n] = 0.0  # rays of fixed points
    else:
        np.matmul(Jpw, VHt[A.own_pg], out=At[:-1])
    np.subtract(prob.ap.Aw, At[:-1], out=At[:-1])
    At[-1] = 0.0
    if A.batched:  # a group per image: one (6 × 2)(2 × k) product per ray,
        # summed by image (the images' ray counts differ: padding them costs more)
        JA = np.matmul(Jew.transpose(0, 2, 1), At[:-1]).reshape(n, 6 * k)
        own = (A.sum_img @ JA).reshape(m, 6, k)
    else:  # one (6 × 2c)(2c × k) product per image over its c rays (the same sums as
        # over its rays padded to the largest count with zero rays, without the padding)
        As = np.take(At, A.by_image, axis=0).reshape(-1, k)
        rows = A.image_rows.tolist()
        if rays is not None and (
            rays.gram.order is A.by_image or np.array_equal(rays.gram.order, A.by_image)
        ):  # the Gram matrices' rays (the same order): J_e is not gathered again
            own = np.zeros((m, 6, k))
            for i, R in rays.of_images():
                own[i] = R[:, :6].T @ As[rows[i] : rows[i + 1]]
        else:
            Js = np.take(Jew, A.by_image, axis=0).reshape(-1, 6)
            own = np.empty((m, 6, k))
            for i in range(m):
                a, b = rows[i], rows[i + 1]
                own[i] = Js[a:b].T @ As[a:b]
    # ... and the blocks of the other groups that its points reach (− Σ T_a H_eᵀ); F:
    # direct term (constant for a linear set; refreshed for a lens model) − Σ H V⁻¹ Hᵀ
    # over the pairs (e, e') of one point
    if A.batched:
        other, Fcorr = batched_terms(A, T, H, HV, k)
        E = BorderE(own, -other, prob.ap.group, A)
        F4 = -Fcorr.reshape(G, G, k, k)
        F4[A.grp_present, A.grp_present] += A.F_direct
    else:
        E = BorderE(own, _other_per_ray(A, T, H, k), prob.ap.group, A)
        F4 = np.zeros((G, G, k, k))
        F4[A.grp_present, A.grp_present] = A.F_direct
        _subtract_per_group_pair(A, F4.reshape(G * G, k, k), VHt, H, k)
    F0 = F4.transpose(0, 2, 1, 3).reshape(prob.q, prob.q)
    F0[np.diag_indices(prob.q)] += prob.ap.w
    return _damped(E, F0, ba, H, lam)


class BorderE:
    """The border E (6m, q) by blocks: each image's 6 × k block of its own group and the
    blocks of the other groups its points reach (a few per cent of E's entries).

    ``E @ v``, ``E.T @ y`` work on the blocks; :meth:`dense` forms the array (kept).
    """

    def __init__(self, own: F64, other: F64, grp, structure: APStructure) -> None:
        self.own, self.other, self.grp, self.s = own, other, grp, structure
        m, _, k = own.shape
        self.k, self.m = k, m
        self.shape = (6 * m, structure.G * k)
        self._dense: F64 | None = None

    def __matmul__(self, v: F64) -> F64:
        vg = v.reshape(self.s.G, self.k)
        out = np.einsum("mrk,mk->mr", self.own, vg[self.grp])
        if self.other.shape[0]:
            ki, gi = np.divmod(self.s.e_key, self.s.G)
            out += self.s.sum_other_img @ np.einsum("nrk,nk->nr", self.other, vg[gi])
        return out.reshape(-1)

    @property
    def T(self) -> _BorderET:
        return _BorderET(self)

    def dense(self) -> F64:
        """E as a (6m, q) array."""
        if self._dense is None:
            G, k, m = self.s.G, self.k, self.m
            E4 = np.zeros((m, 6, G, k))
            E4[np.arange(m), :, self.grp] = self.own
            if self.other.shape[0]:
                ki, gi = np.divmod(self.s.e_key, G)
                E4[ki, :, gi] += self.other
            self._dense = E4.reshape(6 * m, G * k)
        return self._dense

    def permuted(self, pos, dtype=np.float32) -> NDArray:
        """E with its image row blocks moved to ``pos`` (E[p] for the scalar permutation
        p of image order ``perm``, ``pos[perm] = arange(m)``), formed in ``dtype`` directly.

        The other groups' blocks never overlap an image's own group block, so every
        entry is one block's value rounded once: equal to ``dense()[p].astype(dtype)``.
        """
        G, k, m = self.s.G, self.k, self.m
        E4 = np.zeros((m, 6, G, k), dtype)
        E4[pos, :, self.grp] = self.own
        if self.other.shape[0]:
            ki, gi = np.divmod(self.s.e_key, G)
            E4[pos[ki], :, gi] = self.other
        return E4.reshape(6 * m, G * k)


class _BorderET:
    """Eᵀ of a :class:`BorderE`: ``E.T @ y``."""

    def __init__(self, E: BorderE) -> None:
        self.E = E

    def __matmul__(self, y: F64) -> F64:
        E, s = self.E, self.E.s
        y6 = y.reshape(E.m, 6)
        out = s.sum_img_grp @ np.einsum("mrk,mr->mk", E.own, y6)
        if E.other.shape[0]:
            ki, _ = np.divmod(s.e_key, s.G)
            out += s.sum_other_grp @ np.einsum("nrk,nr->nk", E.other, y6[ki])
        return out.reshape(-1)


def dense(E) -> F64:
    """E as an array (a :class:`BorderE` or already an array)."""
    return E.dense() if isinstance(E, BorderE) else E


def _damped(E, F0: F64, ba: F64, H: F64, lam: float) -> APBorder:
    """The border with ``F`` = F0 with its diagonal × (1 + lam)."""
    F = F0.copy() if lam > 0 else F0
    if lam > 0:
        F[np.diag_indices(F.shape[0])] *= 1.0 + lam
    return APBorder(E, F0, F, ba, H)


def point_ap_term(prob, H: F64, da: F64) -> F64:
    """Σ over a point's (point, group) pairs of Hᵀ·da_g, shape (p, 3)."""
    A = prob.ap.structure
    t = np.einsum("nji,nj->ni", H, da.reshape(prob.ap.G, prob.ap.k)[A.pg_grp])
    return A.sum_pt @ t
