"""Auxiliary offsets/drifts and additional parameters as one border of the bundle.

With self-calibration (q additional parameters a) *and* auxiliary data (na offsets and
drifts g per strip) the bundle's reduced camera system S (points eliminated) is
bordered by both kinds of "global" unknowns. They are taken together as one border
b = (a, g) — parameters first, offsets/drifts after them ::

    [ S     E_a    E_g  ] [dc]   [r  ]
    [ E_aᵀ  F_a    F_ag ] [da] = [r_a]
    [ E_gᵀ  F_gaᵀ  F_g  ] [dg]   [r_g]

No observation holds both a and g, so F_ag comes only from the elimination of points
that carry image rays and APR rows: ``F_ag = −Σ_j H_j V_j⁻¹ P_j`` (H_j the rays' Aᵀ P J_p
per (point, group) pair, :mod:`orientviz.bundle.problem._ap_normal`; P_j the APR rows' coupling of
the point with g). The border is eliminated exactly, ``Fs = F − Eᵀ S⁻¹ E`` (forming Fs
with :func:`orientviz.bundle.problem.solve_bordered`); Fs⁻¹ is the cofactor matrix
of the border, which the precision (:func:`orientviz.bundle.precision._precision.bundle_precision`)
needs anyway.

For the precision the border also enters the point blocks: ``h_j = (coupling of point
j with b)ᵀ V_j⁻¹`` (nb, 3) — :func:`point_border` gives g's columns of it — and the
auxiliary observations get redundancy numbers (:func:`auxiliary_redundancy`).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from ...errors import NotDeterminableError
from ..reduced import NormalEquations
from ._ap_normal import dense
from ._border import solve_bordered

F64 = NDArray[np.float64]


def ap_aux_coupling(prob, ne: NormalEquations, Pg: F64) -> F64:
    """F_ag (q, na): the parameters' coupling with the offsets/drifts through the points.

    Parameters
    ----------
    prob : BundleProblem
        With additional parameters (``ap_struct``, ``k``, ``G``).
    ne : dict
        The bundle's normal equations of this iteration (``"H"`` per (point, group)
        pair (npg, k, 3), ``"Vinv"`` (p_var, 3, 3)).
    Pg : ndarray, shape (p_var, 3, na)
        Coupling of each point unknown with the offsets/drifts (APR rows), 1/m².
    """
    A = prob.ap.structure
    na = Pg.shape[2]
    out = np.zeros((prob.ap.G, prob.ap.k, na))
    has = np.any(Pg != 0.0, axis=(1, 2))
    sel = np.flatnonzero(has[A.pg_pt])
    if sel.size:
        pt = A.pg_pt[sel]
        c = ne.ap.H[sel] @ (ne.Vinv[pt] @ Pg[pt])  # (s, k, na)
        np.add.at(out, A.pg_grp[sel], -c)
    return out.reshape(prob.q, na)


def border(prob, ne: NormalEquations) -> tuple[F64, F64, F64]:
    """The joint border: E (6m, q + na), F (q + na, q + na) and its right side (q + na,).

    Without additional parameters (or with them held) the border is g's alone.
    """
    a = ne.aux
    if not prob.q or prob.run.border.hold:
        return a.E, a.F, a.b
    Ea = dense(ne.ap.E_border) if ne.ap is not None else ne.ap.E
    E = np.hstack([Ea, a.E])
    F = np.block([[ne.ap.F, a.Fag], [a.Fag.T, a.F]])
    return E, F, np.concatenate([ne.ap.ba, a.b])


def _not_determinable(prob) -> NotDeterminableError:
    names = list(prob.aux.rows.names)
    if prob.q and not prob.run.border.hold:
        names = list(prob.ap.names) + names
    return NotDeterminableError(
        "the offsets/drifts of the auxiliary data (with the additional parameters, if any) "
        "are not determinable by this block (give control, absolute data or ap_sigma)",
        parameters=names,
    )


def solve_joint(prob, fac, ne: NormalEquations) -> tuple[F64, F64, F64]:
    """Solve the bordered system: (dc (6m,), da (q,), dg (na,)); stores ``ne.Fs_aux``.

    Raises
    ------
    NotDeterminableError
        If the border's Schur complement Fs is not (numerically) positive definite.
    """
    E, F, rb = border(prob, ne)
    if not rb.size:  # absolute data only (no offsets) and no parameters
        ne.Fs_aux = np.zeros((0, 0))
        return fac.solve(ne.rhs), np.zeros(0), np.zeros(0)
    try:
        dc, db, Fs, _ = solve_bordered(fac, E, F, ne.rhs, rb, prob.aux.rows.names)
    except NotDeterminableError:
        raise _not_determinable(prob) from None
    # a scaled Cholesky factor: a nearly singular border (e.g. offsets without any
    # absolute height information) is a defect, not a solution with huge σ
    d = np.sqrt(np.abs(np.diag(Fs))) + 1e-300
    try:
        c = scipy.linalg.cholesky(Fs / np.outer(d, d), lower=True, check_finite=False)
        ok = np.min(np.diag(c)) ** 2 > 1e-12
    except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
        ok = False
    if not ok:
        raise _not_determinable(prob)
    ne.Fs_aux = Fs
    q = db.size - prob.aux.n_global
    return dc, db[:q], db[q:]


def point_border(ne: NormalEquations) -> F64:
    """g's columns of h_j = (point–border coupling)ᵀ V_j⁻¹, shape (p_var, na, 3)."""
    Pg = ne.aux.Pg
    return Pg.transpose(0, 2, 1) @ ne.Vinv


def auxiliary_redundancy(aux, Qcc: F64, Qpp: F64, Qcb: F64, Qbp: F64, Qbb: F64) -> F64:
    """Redundancy numbers r = 1 − w·(J Q Jᵀ)_ii of the auxiliary rows.

    Parameters
    ----------
    aux : BundleAuxiliary
    Qcc : ndarray, shape (m, 6, 6)
        Cofactor blocks of the orientations (m², rad²).
    Qpp : ndarray, shape (p_var, 3, 3)
        Cofactor blocks of the point unknowns (m²).
    Qcb : ndarray, shape (m, 6, nb)
        Orientations × border (additional parameters, then offsets/drifts).
    Qbp : ndarray, shape (p_var, nb, 3)
        Border × points.
    Qbb : ndarray, shape (nb, nb)
        Border.

    Returns
    -------
    ndarray, shape (rows,)
        One redundancy number per auxiliary row (dimensionless, 0 … 1).
    """
    r = aux.rows
    q = Qbb.shape[0] - r.n_global
    on = r.on_image
    t, c = r.target, r.coord
    # the observed coordinate: Q_tt and its cofactors with the border
    Qtt = np.empty(r.n)
    Qtb = np.empty((r.n, Qbb.shape[0]))
    Qtt[on] = Qcc[t[on], c[on], c[on]]
    Qtb[on] = Qcb[t[on], c[on]]
    pc = aux.pcol[~on]
    Qtt[~on] = Qpp[pc, c[~on], c[~on]]
    Qtb[~on] = Qbp[pc, :, c[~on]]
    # the offset/drift part: coefficients j (n, nb), zero where a row has none
    j = np.zeros((r.n, Qbb.shape[0]))
    for k in range(2):
        ok = r.gcol[:, k] >= 0
        j[np.flatnonzero(ok), q + r.gcol[ok, k]] += r.gcoef[ok, k]
    qii = Qtt + 2.0 * np.sum(Qtb * j, axis=1) + np.sum((j @ Qbb) * j, axis=1)
    return 1.0 - r.w * qii
