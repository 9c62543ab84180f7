"""Precision of block adjustments from the reduced system: selected cofactor blocks.

For a bundle block the full cofactor matrix Q = N⁻¹ (u ≈ 130 000 unknowns for 2 100
images) is never formed. What is needed — per-image 6×6 and per-point 3×3 blocks,
redundancy numbers of the image observations — follows *exactly* from the blocks of
Z = S⁻¹ (S the reduced camera system, :mod:`orientviz.bundle.reduced`) at the image
pairs that share a point, i.e. inside the band of S:

* Q_cc = Z (+ Y F̃⁻¹ Yᵀ with self-calibration parameters a, Y = S⁻¹E, F̃ = F − EᵀY),
* Q_pp,j = V_j⁻¹ + Σ_a Σ_b T_aᵀ Q_cc(i_a, i_b) T_b   (T_a = W_a V_j⁻¹, rays a, b of j),
* Q_cp(i, j) = −Σ_b Q_cc(i, i_b) T_b,
* redundancy number of an image coordinate r = 1 − p · (J Q Jᵀ)_kk, and the
  normalised residual w = v / (σ √r) (Baarda, a-priori σ0 = 1),
* the gains of a ray on its own image and point, K = Q_(·, ray) Jᵀ P½ (6×2 and 3×2):
  a bias ∇ (mm) of the ray moves them by K P½ ∇ (external reliability,
  :mod:`orientviz.bundle`).

Z inside the band is computed by the block form of Takahashi's recursion on the banded
Cholesky factor L (S = L Lᵀ): for a block row I with the rows B below it in the band,
Z_IB = −L_II⁻ᵀ L_BIᵀ Z_BB and Z_II = L_II⁻ᵀ (L_II⁻¹ − L_BIᵀ Z_BI). Its cost equals one
factorisation (n·b²), so all numbers here are exact — no approximation. For small
reduced systems (≤ 3 000 unknowns) the dense inverse is used instead.

With self-calibration parameters the border's terms come from
:mod:`orientviz.bundle.precision._precision_ap`: Y = S⁻¹E by two banded triangular solves
with all q columns (BLAS level 3, the same factor as the selected inverse), the
correction Y F̃⁻¹ Yᵀ only at the needed 6×6 blocks, and the point and ray terms per
(point, group) pair with k columns instead of q (a point's rays lie in one or two
groups).

Units: cofactors in the parameters' units squared (m², rad², m·rad); multiply by σ̂0²
for covariances.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from ...blas import blas_threads
from ..problem._ap_normal import dense
from ..reduced import DENSE_CHUNK_BYTES, ReducedStructure, dense_matrix, factor_reduced
from ._band import padded_band, tri_solve
from ._border_points import border_point_terms
from ._camera import camera_precision
from ._far import mark_far, placed_state
from ._pairs import cofactors_by_pairs, point_cofactors, ray_cofactors, var_rows
from ._precision_ap import banded_border, border_inverse, point_terms
from ._store import LAYOUT_FREE_TERMS, fast_layout, ray_blocks, store_precision

F64 = NDArray[np.float64]


def _strided(flat: F64, start: int, shape: tuple[int, int], row_stride: int) -> F64:
    """A read-only (rows, cols) view of ``flat`` from element ``start``: rows step by
    ``row_stride`` elements, columns by one (what BLAS reads in place)."""
    e = flat.itemsize  # np.ndarray on the buffer: the same view as as_strided, made faster
    v = np.ndarray(shape, flat.dtype, flat, start * e, (row_stride * e, e))
    v.flags.writeable = False
    return v


def banded_selected_inverse(
    cb: F64, nb: int = 96, window: int = 12, at: tuple[NDArray, NDArray] | None = None,
    padded: F64 | None = None,
) -> F64:  # fmt: skip
    """Entries of S⁻¹ inside the band, from the banded Cholesky factor of S.

    Parameters
    ----------
    cb : ndarray, shape (kd + 1, n)
        Lower banded Cholesky factor as returned by ``scipy.linalg.cholesky_banded(...,
        lower=True)``: ``cb[d, j] = L[j + d, j]``.
    nb : int
        Block size of the recursion.
    window : int
        Block rows per position of the sliding window (below).
    at : (rows, cols) of int arrays (broadcast together), optional
        Only these entries (inside the band, in the factor's order) are wanted: returned
        in their broadcast shape, read from the window as the recursion passes them (the band itself
        is not stored).
    padded : ndarray, optional
        The factor as :func:`orientviz.bundle.precision._band.padded_band` gives it with at
        least ``nb`` zero rows (read in place); made here when not given.

    Returns
    -------
    ndarray, shape (n, kd + 1) or the shape of ``at``
        ``Zb[i, d] = (S⁻¹)[i, i + d]`` (upper band by rows; zero beyond n), or
        ``(S⁻¹)[rows, cols]``.

    Notes
    -----
    No block is copied before BLAS reads it: L is copied once into band storage with
    ``nb`` zero rows below each column (column stride kd + 1 + nb), so that L_BIᵀ and
    L_IIᵀ of every block row are strided views (row stride kd + nb, unit column stride),
    the zero rows standing for the entries beyond the band and above the diagonal; Z
    lives in a square window that slides up the diagonal of one buffer, so that the Z_BB
    a block row reads is the part its predecessor wrote; every ``window`` block rows the
    window is moved back to the buffer's end (one copy of Z_BB).
    """
    kd, n = cb.shape[0] - 1, cb.shape[1]
    nb = max(1, min(nb, n))
    if padded is None or padded.shape[1] < kd + 1 + nb:
        padded = padded_band(cb, nb)  # a leading zero column: L_IIᵀ of the first block reads it
    C = padded.shape[1]  # column stride of the padded factor
    flat = padded.reshape(-1)
    T = max(1, window) * nb + kd + nb  # the window buffer's size
    buf = np.zeros((T, T + kd + 1))
    W = buf.shape[1]
    bflat = buf.reshape(-1)
    off = max(n - T, 0)  # buffer index = global index − off
    if at is None:
        Zb = np.empty((n, kd + 1))
    else:  # the wanted entries by their smaller index, i.e. by the block row that has them
        at = np.broadcast_arrays(*(np.asarray(a, np.int64) for a in at))
        r, c = (a.reshape(-1) for a in at)
        r, c = np.minimum(r, c), np.maximum(r, c)
        if np.any(c - r > kd):
            raise ValueError("banded_selected_inverse: an entry asked for lies outside the band")
        order = np.argsort(r, kind="stable")
        cut = np.searchsorted(r[order], np.arange(0, n + nb, nb))
        out = np.empty(r.size)
    for k, i0 in reversed(list(enumerate(range(0, n, nb)))):
        i1 = min(i0 + nb, n)
        b1 = min(i1 + kd, n)
        ni, nbb = i1 - i0, b1 - i1
        if i0 < off:  # move the window (its Z_BB) back to the buffer's end
            new = max(b1 - T, 0)
            s, t = i1 - off, i1 - new
            buf[t : t + nbb, t : t + nbb] = buf[s : s + nbb, s : s + nbb].copy()
            off = new
        q = i0 - off
        # L_IIᵀ (upper triangular) starts at L[i0, i0]: element (j + 1)·C + d is L[j + d, j]
        LIIt = _strided(flat, (i0 + 1) * C, (ni, ni), C - 1)
        LIIinv = tri_solve(LIIt.T, np.eye(ni), True, 0)  # L_II⁻¹ = (L_IIᵀ)⁻ᵀ
        if nbb:
            LBIt = _strided(flat, (i0 + 1) * C + ni, (ni, nbb), C - 1)  # L_BIᵀ
            ZBB = buf[q + ni : q + ni + nbb, q + ni : q + ni + nbb]
            ZIB = LIIinv.T @ (LBIt @ ZBB)
            np.negative(ZIB, out=ZIB)
            buf[q : q + ni, q + ni : q + ni + nbb] = ZIB
            buf[q + ni : q + ni + nbb, q : q + ni] = ZIB.T
            buf[q : q + ni, q : q + ni] = LIIinv.T @ (LIIinv - LBIt @ ZIB.T)
        else:
            buf[q : q + ni, q : q + ni] = LIIinv.T @ LIIinv
        if at is None:  # the band rows i0 … i1 − 1: Z[i, i + d] at buffer (q + r, q + r + d);
            # beyond b1 only for the last rows (b1 = n), written first, into the buffer's zeros
            Zb[i0:i1] = _strided(bflat, q * W + q, (ni, kd + 1), W + 1)
        else:  # the wanted entries of these rows (their columns lie in [i0, b1))
            sel = order[cut[k] : cut[k + 1]]
            out[sel] = buf[r[sel] - off, c[sel] - off]
    return Zb if at is None else out.reshape(np.shape(at[0]))


#: Rows per block of the border's solves S⁻¹E (:class:`orientviz.bundle.precision.BandSolver`).
BORDER_SOLVE_BLOCK: int = 64

#: Bands of the inverse up to this many entries (8 bytes each) are computed whole and
#: read by one gather; larger ones give only the wanted entries (``at=``: no band stored).
BAND_GATHER_LIMIT: int = 4_000_000


class ReducedInverse:
    """The inverse of the reduced system S where the precision needs it.

    ``blocks``: the 6×6 blocks of Z = S⁻¹ at the structure's blocks (i ≤ k), shape
    (nb, 6, 6); :meth:`border` gives S⁻¹E for a border E (self-calibration) from the same
    factorisation. ``fac``: an existing banded factor of S (from
    :func:`orientviz.bundle.reduced.factor_reduced` on the same blocks), then not
    factored again. ``dense_limit``: up to this many unknowns Z is computed densely;
    ``nb``: block size of the banded selected inverse.
    """

    def __init__(
        self, st: ReducedStructure, blocks: F64, fac=None, dense_limit: int = 3000, nb: int = 96
    ) -> None:
        n = st.n_reduced
        r6 = np.arange(6)
        self._Z = self._fac = self._padded = None
        self._m = st.n_cam
        if n <= dense_limit or st.solver != "banded":
            if n > dense_limit and st.solver != "dense":
                st = ReducedStructure(
                    st.obs_cam,
                    st.obs_pt,
                    st.n_cam,
                    st.n_pt,
                    solver="banded",
                    positions=st.positions,
                    options=st.options,
                )
            else:  # dense: the factor of the last iteration when it is a dense one
                if fac is not None and fac.kind == "dense":
                    c = (fac.data, True)
                else:
                    c = scipy.linalg.cho_factor(dense_matrix(st, blocks), lower=True)
                eye = np.eye(n, order="F")  # (LAPACK's layout: solved in place, not copied)
                Z = self._Z = scipy.linalg.cho_solve(c, eye, overwrite_b=True)
                rows = 6 * st.block_i[:, None, None] + r6[None, :, None]
                cols = 6 * st.block_k[:, None, None] + r6[None, None, :]
                self.blocks = Z[rows, cols]
                return
        if fac is None or fac.kind != "banded":
            fac = factor_reduced(st, blocks)
        self._fac = fac
        # one padded copy of the factor for the inverse and the border's solves
        pad = self._padded = padded_band(fac.data, max(nb, BORDER_SOLVE_BLOCK))
        p = st.pos_img
        rows = 6 * p[st.block_i][:, None, None] + r6[None, :, None]
        cols = 6 * p[st.block_k][:, None, None] + r6[None, None, :]
        if fac.data.size <= BAND_GATHER_LIMIT:  # the whole band, then one gather (faster)
            Zb = banded_selected_inverse(fac.data, nb, padded=pad)
            flat = np.minimum(rows, cols) * Zb.shape[1] + np.abs(rows - cols)
            self.blocks = Zb.reshape(-1).take(flat)
        else:  # only the wanted entries (the band is not stored)
            self.blocks = banded_selected_inverse(fac.data, nb, at=(rows, cols), padded=pad)

    def border(self, E) -> tuple[F64, F64, NDArray[np.int64]]:
        """S⁻¹E and Eᵀ S⁻¹ E for a border E (6m, q): ``(Y3, EtY, row)``.

        ``Y3`` (m, 6, q) holds the 6 rows of image i at ``Y3[row[i]]`` (the banded
        factor's image order: no reordering pass over the (6m, q) array). ``E`` is an
        array or a :class:`~orientviz.bundle.problem._ap_normal.BorderE`.
        """
        m = self._m
        if self._Z is not None:
            E = dense(E)
            Y = self._Z @ E
            EtY = E.T @ Y
            return Y.reshape(m, 6, -1), 0.5 * (EtY + EtY.T), np.arange(m)
        st = self._fac.structure
        Yp, EtY = banded_border(
            self._fac.data, st.scalar_perm, E, st.pos_img, BORDER_SOLVE_BLOCK, self._padded
        )
        return Yp.reshape(m, 6, -1), EtY, st.pos_img


#: Blocks of S corrected at once by :func:`_with_border` (its gathers ≈ 2 MB each).
BORDER_CHUNK: int = 1024


def _with_border(Zblk: F64, Qca: F64, Y3: F64, bi, bk) -> F64:
    """Zblk − Qca[i] Y3[k]ᵀ at every block (i, k) of S, in chunks of :data:`BORDER_CHUNK`
    blocks (a new array; the same products as at once, without (blocks, 6, nb) gathers of
    many MB in fresh memory)."""
    out = np.empty_like(Zblk)
    for s0 in range(0, Zblk.shape[0], BORDER_CHUNK):
        sl = slice(s0, s0 + BORDER_CHUNK)
        out[sl] = Zblk[sl] - Qca[bi[sl]] @ Y3[bk[sl]].transpose(0, 2, 1)
    return out


def cofactors_image_point(S, Z: F64, T: F64, oi, ocol, Qcp: F64) -> bool:
    """Q_cp of each ray by products with the dense inverse Z = S⁻¹: for a chunk of points,
    Z (n × n) times their T_b placed at the rows of their images (n × 3p_chunk), read at
    each ray's image rows. Σ k_j² pairs of rays become (6m)²·3p multiply-adds at BLAS
    speed (what a network whose points are seen by most images needs). False (nothing
    done) when a point has two rays in one image."""
    rays = S.pt_obs
    img, col = oi[rays], ocol[rays]
    m, n = S.n_cam, S.n_reduced
    if np.unique(col * m + img).size != rays.size:
        return False
    pc = max(1, DENSE_CHUNK_BYTES // (8 * 18 * m))
    starts = np.append(S.pt_starts, rays.size)
    for p0 in range(0, S.n_pt, pc):
        p1 = min(p0 + pc, S.n_pt)
        r = slice(starts[p0], starts[p1])
        Tf = np.zeros((m, 6, p1 - p0, 3))
        Tf[img[r], :, col[r] - p0, :] = T[rays[r]]
        M = (Z @ Tf.reshape(n, -1)).reshape(m, 6, p1 - p0, 3)
        Qcp[rays[r]] = -M[img[r], :, col[r] - p0, :]
    return True


def bundle_precision(res, prob, st, rw, Je, Jp, lin=None) -> None:
    """Fill ``res`` with cofactor blocks, redundancy numbers and normalised residuals.

    Also ``redundancy_xy`` (n,) and ``ray_gains`` = ``RayGains(exterior (n, 6, 2),
    points (n, 3, 2))`` per image observation (NaN for unused rays; zero
    point gains for fixed points): the change of the ray's image orientation (m, rad) and
    point (m) per unit change of its x, y in units of their σ.

    Parameters
    ----------
    res : Adjustment
        The bundle result (residual order as in :mod:`orientviz.bundle._result`).
    prob : BundleProblem
    st : state at the solution; rw, Je, Jp : weighted misclosures and Jacobians there.
    lin : tuple, optional
        ``(ne, fac, Je, Jp)`` of the last Gauss-Newton iteration — its normal equations,
        the factor of its reduced system and the Jacobians they were built from. The
        cofactors are then those of that linearisation point, which the final
        correction moved by less than the stopping tolerance (a few thousandths of a
        conditional σ); the normal equations are not built and factored again.

    Notes
    -----
    BLAS runs on one thread here (threadpoolctl): the pass is made of many small
    products, for which a second BLAS thread mostly waits; it cost several times the
    CPU and no wall time was gained (benchmarks/README.md, "the precision pass on one
    BLAS thread").
    """
    with blas_threads(1):
        _fill_precision(res, prob, st, rw, Je, Jp, lin)


def _fill_precision(res, prob, st, rw, Je, Jp, lin) -> None:
    """The work of :func:`bundle_precision` (same arguments)."""
    fac, far = None, None
    if lin is not None:
        ne, fac, Je, Jp = lin
    else:  # points near infinity: placed where their depth is defined (._far)
        st_p, far = placed_state(prob, st)
        if far.size:  # their rays at the placed points (the others' as they are)
            rays = np.flatnonzero(np.isin(prob.obs.column, far))
            rw, Je, Jp = prob.residuals_of_rays(st_p, rays, rw, Je, Jp)
        ne = prob.normal(st_p, rw, Je, Jp)
    if ne.ext is not None:  # the cameras inside the images' blocks: their own form
        camera_precision(res, prob, ne, Je, Jp)
    else:
        _fill_from(res, prob, ne, fac, Je, Jp)
    if far is not None:
        mark_far(res, prob, far)


def _fill_from(res, prob, ne, fac, Je, Jp) -> None:
    """The precision from the normal equations ``ne`` at the solution (``fac``: the
    factor of its reduced system when there is one); the rest as :func:`_fill_precision`."""
    S = prob.reduced
    blocks = ne.blocks
    opts = prob.options
    inverse = ReducedInverse(S, blocks, fac, opts.dense_inverse_limit, opts.takahashi_block)
    Zblk = inverse.blocks
    m, q = prob.m, prob.q
    aux = getattr(prob, "aux", None)
    nb = q + (prob.na if aux else 0)  # border: additional parameters, auxiliary offsets
    fast_ap = bool(q) and not aux
    if fast_ap:  # parameters only: the banded border path (bundle_precision_ap)
        E = ne.ap.E_border if ne.ap is not None else ne.ap.E
        Faa, Qca3, dQ = border_inverse(inverse, E, ne.ap.F, S)
        Zblk = Zblk + dQ
    elif nb:  # auxiliary offsets/drifts (and parameters): the whole border densely
        E, F = aux.border(prob, ne)
        Y3, EtY, row = inverse.border(E)  # S⁻¹E by the same factor (BLAS 3)
        Y3 = Y3[row]  # image order
        Faa = np.linalg.inv(F - EtY)  # Q_aa (of the whole border)
        Qca = -(Y3 @ Faa)  # (m, 6, nb)
        Zblk = _with_border(Zblk, Qca, Y3, S.block_i, S.block_k)  # + Y Q_aa Yᵀ
    Qcc_diag = Zblk[S.diag_block]
    # point cofactors: Vinv + Σ_ab T_aᵀ Q(i_a, i_b) T_b
    oi, ocol = prob.obs.image, prob.obs.column
    T = ne.T
    n_used = oi.size
    # Q_cp for each observation a: −Σ_b Q(i_a, i_b) T_b  (then add the AP part)
    Vinv = ne.Vinv
    vo = prob.obs.var_rays  # the rays of point unknowns in point order (the border's sums)
    rv = var_rows(prob.obs)  # the same rays in their own order (per-ray products)
    sw = prob.obs.weight
    Jew = Je * sw[:, :, None]
    Jpw = Jp * sw[:, :, None]
    dense_qcp = inverse._Z is not None and not nb and S.formation == "dense"
    if dense_qcp:  # dense S formed densely: Q_cp by products with the dense inverse
        Qcp = np.zeros((n_used, 6, 3))
        dense_qcp = cofactors_image_point(S, inverse._Z, T, oi, ocol, Qcp)
    if fast_ap:  # the parameters' terms, sparse by (ray, group) and (point, group) pairs
        dQcp, dQpp, Qap_pg, Hray = point_terms(prob, ne, Faa, Qca3, Jew, Jpw)
    if (not nb or fast_ap) and not dense_qcp:  # Q_cp, Q_pp and the rays' blocks in one pass
        minus = (dQcp, dQpp) if fast_ap else (None, None)
        Qpp, Ke, Kp, H = ray_cofactors(S, Zblk, T, Vinv, Qcc_diag, oi, Jew, Jpw, *minus)
    else:
        if not dense_qcp:
            Qcp = np.zeros((n_used, 6, 3))
            cofactors_by_pairs(S, Zblk, T, Qcp)
        if nb:
            hb = np.zeros((S.n_pt, nb, 3))  # Σ_b Tap_b placed in its group columns
            if q:
                Tap = (prob.ap.Aw[vo].transpose(0, 2, 1) @ Jpw[vo]) @ Vinv[ocol[vo]]
                g = prob.ap.group[oi[vo]]
                cols = g[:, None] * prob.ap.k + np.arange(prob.ap.k)
                np.add.at(hb, (ocol[vo][:, None], cols), Tap)
            aux.point_border(prob, ne, hb)
            # Q_cp −= Q_ca h_j, Q_pp,j −= h_jᵀ Q_ap,j with Q_ap,j = −(Σ_b Q_ca(i_b)ᵀ T_b + Q_aa h_j)
            # at the points the border couples (every point with additional parameters)
            vo_idx = np.arange(n_used)[vo]
            Qpp, Qap = border_point_terms(S, oi, vo_idx, ocol, T, Qca, Faa, hb, Qcp, Vinv, bool(q))
        else:  # Q_pp,j = V_j⁻¹ − Σ_b T_bᵀ Q_cp(i_b, j)
            Qpp = point_cofactors(Vinv, T, Qcp, S)
        # gains of each ray on its own image and point, K = Q_(·, ray) Jwᵀ: the change of
        # the estimates per σ-normalised change of the ray's x, y (external reliability);
        # first without the parameters' terms; 2×2 block of P½ J Q Jᵀ P½ per image
        # observation = Jw K (batched products, no full Q): redundancy numbers r = 1 −
        # diagonal, off-diagonal of P½ Q_vv P½ = −(J Q Jᵀ)_xy
        Ke, Kp, H = ray_blocks(Qcc_diag, oi, Qcp, Qpp, Jew, Jpw[rv], rv, ocol[rv])
    if fast_ap:
        H += Hray
    elif q:  # the parameters' terms of the rays, from the dense border cofactors
        Aw = prob.ap.Aw
        sl = np.arange(prob.ap.k)[None, :] + prob.ap.k * prob.ap.group[oi][:, None]  # (n, k)
        Qaa_o = Faa[sl[:, :, None], sl[:, None, :]]
        Qca_o = np.take_along_axis(Qca[oi], np.repeat(sl[:, None, :], 6, 1), axis=2)
        AwT = Aw.transpose(0, 2, 1)
        C = (Jew @ Qca_o) @ AwT
        H += (Aw @ Qaa_o) @ AwT + C + C.transpose(0, 2, 1)
        Qpa = Qap.transpose(0, 2, 1)[ocol[rv]]  # (nv, 3, nb)
        Qpa_o = np.take_along_axis(Qpa, np.repeat(sl[rv][:, None, :], 3, 1), axis=2)
        C = (Jpw[rv] @ Qpa_o) @ AwT[rv]
        H[rv] += C + C.transpose(0, 2, 1)
    if q:  # the gains' terms of Q_ca, Q_pa in the ray's own group's k columns
        if fast_ap:
            Qca_o = Qca3.reshape(m, 6, prob.ap.G, prob.ap.k)[np.arange(m), :, prob.ap.group, :][oi]
            own, k = prob.ap.structure.own_pg[rv], prob.ap.k
            if k < LAYOUT_FREE_TERMS:  # contiguous: the same numbers, read faster (fast_layout)
                Qpa_o = np.ascontiguousarray(Qap_pg.transpose(0, 2, 1))[own]
            else:
                Qpa_o = Qap_pg[own].transpose(0, 2, 1)
            AwT = fast_layout(prob.ap.Aw.transpose(0, 2, 1), k)
        Ke += Qca_o @ AwT
        Kp[rv] += Qpa_o @ AwT[rv]
    faa = Faa[:q, :q] if q else None
    auxiliary = None
    if aux:  # redundancy numbers of the auxiliary rows, cofactors of the offsets
        if not nb:
            Qca, Qap, Faa = np.zeros((m, 6, 0)), np.zeros((S.n_pt, 0, 3)), np.zeros((0, 0))
        aux_args = (res, Qcc_diag, Qpp, Qca, Qap, Faa)
        auxiliary = lambda: aux.precision(*aux_args)  # noqa: E731
    store_precision(
        res, prob, H=H, Qpp=Qpp, Qext=Qcc_diag, pairs=Zblk, Faa=faa, Ke=Ke,
        Kp=Kp, auxiliary=auxiliary,
    )  # fmt: skip
