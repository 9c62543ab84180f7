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
once per problem (:class:`~._ap_structure.APStructure`) and applied as sparse 0/1 products; no
``np.add.at``.

How the border is then eliminated: :mod:`orientviz.bundle.problem._border`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..reduced import APBorder, ImageRays
from ._ap_batches import batched_terms
from ._ap_structure import APStructure

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


def _ssum(M: sp.csr_matrix, X: F64) -> F64:
    """Row sums of X (N, a, b) → (K, a, b) by a summation matrix of :mod:`._ap_structure`."""
    return np.asarray(M @ X.reshape(X.shape[0], -1)).reshape((M.shape[0],) + X.shape[1:])


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
