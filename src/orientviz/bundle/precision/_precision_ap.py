"""Cofactors of a self-calibrating bundle: the additional-parameter terms, sparse by group.

:func:`orientviz.bundle.precision._precision.bundle_precision` computes the cofactor blocks of a
bundle from the reduced camera system S. With q = G·k additional parameters in G groups
the reduced system is bordered ::

    [ S   E ]        Q_aa = Fs⁻¹, Fs = F − Eᵀ S⁻¹ E
    [ Eᵀ  F ]        Q_ca = −Y Q_aa,  Y = S⁻¹ E,   Q_cc = S⁻¹ + Y Q_aa Yᵀ

This module supplies the border's part:

* :func:`border_inverse` — Y, Q_aa, Q_ca from two banded triangular solves with all q
  columns at once (BLAS level 3 on views of the factor, :class:`._band.BandSolver`), and
  the correction Y Q_aa Yᵀ of the 6 × 6 blocks of Q_cc that the precision needs (one
  product per image row of blocks, never the dense 6m × 6m matrix);
* :func:`point_terms` — the terms of the points and of the image rays. A point's
  coupling with the parameters (``H V⁻¹`` per (point, group) pair) is non-zero only in
  the columns of the groups its rays lie in, a ray's design only in its own group's
  columns; everything is therefore computed per (ray, group of its point) and
  (point, group) pair with k columns, not with all q.

Cost: the two banded solves dominate (about 2·n·kd·q flops each, n = 6m, kd the
half-bandwidth).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse as sp
from numpy.typing import NDArray

from ..problem._ap_normal import BorderE
from ._band import BandSolver
from ._pairs import var_rows
from ._store import fast_layout

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


def border_inverse(inverse, E: F64, F: F64, st) -> tuple[F64, F64, F64]:
    """Q_aa, Q_ca (m, 6, q) and the Q_cc correction at the structure's blocks.

    Parameters
    ----------
    inverse : orientviz.bundle.precision._precision.ReducedInverse
        The inverse of S (dense or its banded Cholesky factor).
    E : ndarray, shape (6m, q), or orientviz.bundle.problem._ap_normal.BorderE
        Border (points eliminated).
    F : ndarray, shape (q, q)
        Parameter block (points eliminated, pseudo-observations included).
    st : orientviz.bundle.reduced.ReducedStructure
        Blocks (i ≤ k) where the correction is wanted (``block_i`` sorted).

    Returns
    -------
    Qaa : ndarray, shape (q, q)
    Qca : ndarray, shape (m, 6, q)
    dQcc : ndarray, shape (n_blocks, 6, 6)
        (Y Q_aa Yᵀ) at the blocks (block_i, block_k).
    """
    Y3, EtY, row = inverse.border(E)
    Fs = F - EtY
    c = scipy.linalg.cho_factor(Fs, lower=True, check_finite=False)
    Qaa = scipy.linalg.cho_solve(c, np.eye(F.shape[0]), check_finite=False)
    Qaa = 0.5 * (Qaa + Qaa.T)
    m, q = st.n_cam, F.shape[0]
    Qca3 = -(Y3.reshape(-1, q) @ Qaa).reshape(m, 6, q)[row]  # in image order
    dQ = np.empty((st.n_blocks, 6, 6))
    seg = np.searchsorted(st.block_i, np.arange(m + 1))
    for i in range(m):
        a, b = seg[i], seg[i + 1]
        if b > a:  # Y_i Q_aa Y_kᵀ = −Q_ca,i Y_kᵀ for all blocks (i, k) in one product
            P = Qca3[i] @ Y3[row[st.block_k[a:b]]].reshape(-1, q).T  # (6, 6·nk)
            dQ[a:b] = -P.reshape(6, b - a, 6).transpose(1, 0, 2)
    return Qaa, Qca3, dQ


def banded_border(
    L: F64, perm: I64, E, pos: I64, nb: int = 64, padded: F64 | None = None
) -> tuple[F64, F64]:
    """S⁻¹ E and Eᵀ S⁻¹ E from the banded Cholesky factor L of S (rows permuted).

    Parameters
    ----------
    L : ndarray, shape (kd + 1, n)
        Lower band factor of S[perm][:, perm].
    perm : ndarray of int, shape (n,)
        Scalar permutation of the factor (6 rows per image).
    E : ndarray, shape (n, q), or orientviz.bundle.problem._ap_normal.BorderE
    pos : ndarray of int, shape (m,)
        Position of each image in the factor's order (``perm`` by images).
    nb, padded : int, ndarray, optional
        Rows per block of the solves and the padded factor
        (:class:`orientviz.bundle.precision.BandSolver`).

    Returns
    -------
    Yp : ndarray, shape (n, q)
        S⁻¹ E in the factor's row order: ``Yp[k] = (S⁻¹E)[perm[k]]``.
    EtY : ndarray, shape (q, q)
        Eᵀ S⁻¹ E = ZᵀZ with Z = L⁻¹ E (symmetric by construction).
    """
    Ep = E.permuted(pos, np.float64) if isinstance(E, BorderE) else E[perm]
    band = BandSolver(L, nb, padded)
    Z = band.forward(Ep)
    del Ep
    C = scipy.linalg.blas.dsyrk(1.0, Z.T)  # upper triangle of ZᵀZ
    EtY = np.triu(C) + np.triu(C, 1).T
    return band.backward(Z), EtY


@dataclass
class RayGroupPairs:
    """Index maps of the sparse parameter terms (constant for a problem).

    The rays of an image in their own group are handled in the per-image padded layout
    of :class:`~orientviz.bundle.problem._ap_structure.APStructure` (``pad``, (m, L)): ``slot`` is
    each ray's place in it (i·L + column), ``sum_own`` sums the padded slots by the own
    (point, group) pair of their ray. The (ray, pair of another group of its point)
    products (``APStructure.e_obs``, ``e_pg``) are summed by ray and by pair in
    :func:`_pair_sums`, from ``by_ray``/``ray_starts`` and ``by_pg``/``pg_starts`` (the
    products in row order and where each row's begin); ``sum_f`` sums the (point, group)
    pairs of one point (``APStructure.f_1``, ``f_2``) by ``f_1``; ``by_group``/
    ``group_starts``: the rays ordered by group.
    """

    slot: I64
    sum_own: sp.csr_matrix
    by_ray: I64
    ray_starts: I64
    by_pg: I64
    pg_starts: I64
    sum_f: sp.csr_matrix
    by_group: I64
    group_starts: I64


#: Products of (ray, other pair) handled at once by :func:`_pair_sums` (about 1–2 MB
#: per temporary): the gathers and products stay in cache and reuse their memory.
PAIR_CHUNK: int = 8192


def _summation(rows: I64, n_rows: int) -> sp.csr_matrix:
    """Sparse 0/1 matrix that adds the entries with equal ``rows`` value."""
    return sp.csr_matrix(
        (np.ones(rows.size), (rows, np.arange(rows.size))), shape=(n_rows, rows.size)
    )


def _row_order(rows: I64, n_rows: int) -> tuple[I64, I64]:
    """The entries ordered by ``rows`` (stable: ascending entry within a row) and where
    each row's entries begin (``n_rows + 1``): the column order of :func:`_summation`'s
    matrix, whose rows add their entries in that order."""
    order = np.argsort(rows, kind="stable")
    starts = np.zeros(n_rows + 1, np.int64)
    np.cumsum(np.bincount(rows, minlength=n_rows), out=starts[1:])
    return order, starts


def _pair_sums(out: F64, order: I64, starts: I64, product) -> None:
    """``out[r] += Σ product(e)`` over the entries e of each row r, in chunks of about
    :data:`PAIR_CHUNK` entries (whole rows).

    ``product(entries)`` returns the entries' terms (len, …) with ``out``'s trailing
    shape. Each row adds its terms from zero in ascending entry order (a sparse 0/1
    matrix's product, as :func:`_summation`'s over all entries at once: the same sums).
    """
    n_rows = starts.size - 1
    width = int(np.prod(out.shape[1:]))
    flat = out.reshape(n_rows, width)
    r0 = 0
    while r0 < n_rows:
        r1 = int(np.searchsorted(starts, starts[r0] + PAIR_CHUNK, side="right")) - 1
        r1 = min(max(r1, r0 + 1), n_rows)
        a, b = starts[r0], starts[r1]
        if b > a:
            local = sp.csr_matrix(
                (np.ones(b - a), np.arange(b - a), starts[r0 : r1 + 1] - a), shape=(r1 - r0, b - a)
            )
            flat[r0:r1] += local @ product(order[a:b]).reshape(b - a, width)
        else:
            flat[r0:r1] += 0.0  # as a product of empty rows adds (−0.0 becomes 0.0)
        r0 = r1


def ray_group_pairs(prob) -> RayGroupPairs:
    """The :class:`RayGroupPairs` of a bundle problem, from its additional parameters'
    structure (computed at each call)."""
    A = prob.ap.structure
    n, npg = prob.obs.image.size, A.pg_pt.size
    pad = A.pad.reshape(-1)
    slot = np.zeros(n + 1, np.int64)
    slot[pad] = np.arange(pad.size)  # the padding entries (n) land in slot[n], unused
    real = pad < n
    own_slot = np.full(pad.size, npg, np.int64)
    own_slot[real] = A.own_pg[pad[real]]
    ok = own_slot < npg  # slots of rays of point unknowns
    sum_own = sp.csr_matrix(
        (np.ones(int(ok.sum())), (own_slot[ok], np.flatnonzero(ok))), shape=(npg, pad.size)
    )
    go = prob.ap.group[prob.obs.image]
    by_group = np.argsort(go, kind="stable")
    group_starts = np.searchsorted(go[by_group], np.arange(prob.ap.G + 1))
    by_ray, ray_starts = _row_order(A.e_obs, n)
    by_pg, pg_starts = _row_order(A.e_pg, npg)
    out = RayGroupPairs(
        slot[:n],
        sum_own,
        by_ray,
        ray_starts,
        by_pg,
        pg_starts,
        _summation(A.f_1, npg),
        by_group,
        group_starts,
    )
    return out


def point_terms(prob, ne, Qaa: F64, Qca3: F64, Jew: F64, Jpw: F64):
    """The parameter terms of the point cofactors and of the rays' 2 × 2 blocks.

    Parameters
    ----------
    prob : BundleProblem
    ne : dict
        Normal equations at the solution (``H``, ``Vinv``, ``T``).
    Qaa : ndarray, shape (q, q)
    Qca3 : ndarray, shape (m, 6, q)
    Jew, Jpw : ndarray, shapes (n, 2, 6), (n, 2, 3)
        Weighted Jacobians at the solution.

    Returns
    -------
    dQcp : ndarray, shape (n, 6, 3)
        To subtract from Q_cp of each ray of a point unknown: Σ_e Q_ca(i_a, g_e) HV_e over
        its point's (point, group) pairs (rows of other rays not meaningful).
    dQpp : ndarray, shape (p_var, 3, 3)
        To subtract from Q_pp: Σ over a point's (point, group) pairs of HV_eᵀ Q_ap,e.
    Qap : ndarray, shape (npg, k, 3)
        Q_ap per (point, group) pair (the point's rows of Q_ap in that group's columns).
    Hray : ndarray, shape (n, 2, 2)
        The parameter terms of J Q Jᵀ per ray (to add).
    """
    A = prob.ap.structure
    R = ray_group_pairs(prob)
    G, k, m = prob.ap.G, prob.ap.k, prob.m
    L = A.pad.shape[1]
    Vinv, T = ne.Vinv, ne.T
    HV = ne.ap.H @ Vinv[A.pg_pt]  # (npg, k, 3): H V⁻¹, the point's coupling with group g
    Qca4 = Qca3.reshape(m, 6, G, k)
    Qca_own = Qca4[np.arange(m), :, prob.ap.group, :]  # (m, 6, k): each image's own group
    oi = prob.obs.image
    # own group, per ray (Q_ca,own of its image; zero HV rows for rays of fixed points)
    HVz = np.concatenate([HV, np.zeros((1, k, 3))])
    Qo = Qca_own[oi]  # (n, 6, k)
    # Q_cp(i_a, j) −= Σ_e Q_ca(i_a, g_e) HV_e: own group ...
    t = Qo @ HVz[A.own_pg]
    # ... and the other groups of the ray's point: Q_ca(i_a, g_e) per (ray, pair) from
    # the (image, group) blocks of Q_ca, (m·G, 6, k)
    Qig = np.ascontiguousarray(Qca4.transpose(0, 2, 1, 3)).reshape(m * G, 6, k)
    e_obs, e_pg = A.e_obs, A.e_pg
    e_rows = oi[e_obs] * G + A.pg_grp[e_pg]
    if e_obs.size:
        _pair_sums(t, R.by_ray, R.ray_starts, lambda e: Qig[e_rows[e]] @ HV[e_pg[e]])
    dQcp = t
    # Q_ap,e = −(Σ_b Q_ca(i_b, g_e)ᵀ T_b + Σ_e' Q_aa(g_e, g_e') HV_e'): own group ...
    t = np.zeros((m * L, k * 3))  # in the padded layout, summed by slot
    t[R.slot] = (Qo.transpose(0, 2, 1) @ T).reshape(-1, k * 3)
    Qap = R.sum_own @ t
    # ... and the pairs of other groups
    if e_obs.size:
        _pair_sums(
            Qap, R.by_pg, R.pg_starts, lambda e: Qig[e_rows[e]].transpose(0, 2, 1) @ T[e_obs[e]]
        )
    Qap = Qap.reshape(-1, k, 3)
    # the second sum: one product per pair of groups (g_e, g_e') over all its pairs
    # (transposed: (HV_e'ᵀ Q_aa(g_e', g_e)) (3 × k) per pair, all pairs of (g1, g2) in one
    # product (Q_aa symmetric: Q_aa(g_e, g_e')ᵀ = Q_aa(g_e', g_e)))
    HVT2 = np.ascontiguousarray(HV.transpose(0, 2, 1))[A.f_2]  # (pairs, 3, k)
    t = np.empty_like(HVT2)
    for key, a, b in zip(A.f_key, A.f_bounds[:-1], A.f_bounds[1:]):
        g1, g2 = divmod(int(key), G)
        Fb = Qaa[g2 * k : (g2 + 1) * k, g1 * k : (g1 + 1) * k]
        t[a:b] = (HVT2[a:b].reshape(-1, k) @ Fb).reshape(-1, 3, k)
    tsum = (R.sum_f @ t.reshape(t.shape[0], -1)).reshape(-1, 3, k)
    Qap = -(Qap + tsum.transpose(0, 2, 1))
    # Q_pp −= Σ_e HV_eᵀ Q_ap,e, per point
    t = HV.transpose(0, 2, 1) @ Qap
    dQpp = (A.sum_pt @ t.reshape(t.shape[0], -1)).reshape(-1, 3, 3)
    # rays: A Q_aa Aᵀ + 2 sym(J_e Q_ca Aᵀ) (+ 2 sym(J_p Q_pa Aᵀ) for point unknowns),
    # all in the ray's own group's k columns
    Aw = prob.ap.Aw
    AQ = np.empty_like(Aw)
    for g in range(G):
        idx = R.by_group[R.group_starts[g] : R.group_starts[g + 1]]
        if idx.size:
            Fg = Qaa[g * k : (g + 1) * k, g * k : (g + 1) * k]
            AQ[idx] = (Aw[idx].reshape(-1, k) @ Fg).reshape(-1, 2, k)
    Jpad = Jew[A.pad0].reshape(m, 2 * L, 6)  # J_e Q_ca,own per image, then per ray
    JQ = np.matmul(Jpad, Qca_own).reshape(m * L, 2, k)[R.slot]
    vo = var_rows(prob.obs)  # the rays of point unknowns (a slice when they come first)
    # the transposed right-hand factors as contiguous copies where that gives the same
    # numbers (read faster: ._store.fast_layout)
    QapT = fast_layout(Qap.transpose(0, 2, 1), 3)
    JQ[vo] += Jpw[vo] @ QapT[A.own_pg[vo]]
    AwT = fast_layout(Aw.transpose(0, 2, 1), k)
    C = JQ @ AwT
    AQ += JQ  # (A Q_aa + J Q) Aᵀ + (J Q Aᵀ)ᵀ
    Hray = AQ @ AwT + C.transpose(0, 2, 1)
    return dQcp, dQpp, Qap, Hray
