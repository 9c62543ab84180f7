"""Independent models with extra unknowns: model deformation parameters and auxiliary data.

The rigorous 7-parameter adjustment of :mod:`orientviz.stereo_models`, extended by

* model deformation parameters p (:mod:`orientviz.stereo_models._deformation`) per
  model, strip or block: the model coordinates carry the deformation A(m)·p, so
  ``X + v = λ R (m − A(m)·p) + T``, with pseudo-observations p = 0 ± σ (mm);
* auxiliary observations (:mod:`orientviz.bundle.problem._auxiliary`) of projection centres
  (GNSS, statoscope) and tie points (APR), with offset/drift unknowns per strip.

The extra unknowns ("globals") join the 7 parameters of every model in the reduced
system; every row still observes at most one scalar point coordinate, so the point part
stays diagonal and is eliminated as before (:func:`~.models_normal.solve_sparse`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..adjust import Evaluation, Step, iterate
from ..block import AuxiliaryEstimates, check_points_of
from ..bundle import analyse
from ..bundle.problem import AuxRows, auxiliary_rows
from ..errors import InputError, NotDeterminableError
from ..rotation import matrix_from_rotvec, skew
from ._deformation import DeformationField, ModelDeformation, group_index
from ._normal import scalar_cofactors, solve_sparse
from ._result import DeformationEstimates, ModelsResult
from ._steps import stop_rule

F64 = NDArray[np.float64]
#: Above this many similarity parameters (7 per model) their correlations with the
#: deformation parameters are not computed.
SIMILARITY_CHECK_LIMIT: int = 7 * 1000


@dataclasses.dataclass
class JointSetup:
    """Extra unknowns of a joint independent-model adjustment."""

    deform: ModelDeformation | None
    field: DeformationField | None
    A: F64  # (k_rows, 3, q) fields at the rows
    group: NDArray[np.int64]  # (n_models,)
    n_groups: int
    sigma: F64  # (q,) mm, inf = free
    aux: AuxRows | None
    aux_scalar: NDArray[np.int64]  # (n_aux,) scalar unknown (−1 fixed)
    aux_tie: NDArray[np.int64]  # (n_aux,) tie index

    @property
    def q(self) -> int:
        return self.A.shape[2]

    @property
    def n_def(self) -> int:
        return self.n_groups * self.q

    @property
    def n_aux(self) -> int:
        return self.aux.n_global if self.aux is not None else 0

    def names(self, ms) -> list[str]:
        out = []
        if self.deform is not None:
            labels = _group_labels(self.group, ms)
            out += [f"{t}@{labels[g]}" for g in range(self.n_groups) for t in self.deform.terms]
        return out + (list(self.aux.names) if self.aux is not None else [])


def _group_labels(group, ms) -> list[str]:
    labels = []
    for g in range(int(group.max()) + 1):
        members = np.flatnonzero(group == g)
        if members.size == 1:
            labels.append(ms.ids[members[0]])
        elif members.size == ms.n_models:
            labels.append("block")
        else:
            labels.append(f"strip{int(ms.strip[members[0]])}")
    return labels


def joint_setup(block, ms, su, w_c, deformation, group, sigma, auxiliary) -> JointSetup:
    """Fields, groups and auxiliary rows (see :func:`orientviz.stereo_models.independent_models`)."""
    n_rows = su.row_model.size
    ground = su.row_point < su.tie_points.size
    if deformation is not None:
        fld = deformation.fit(su.m, su.row_model, ground, w_c, ms.n_models)
        A = fld.evaluate(su.m, su.row_model, ground)
        grp = group_index(group, ms.strip)
        s = np.broadcast_to(
            np.asarray(np.inf if sigma is None else sigma, float), (deformation.k,)
        ).copy()
        if np.any(~(s > 0)):
            raise InputError(f"deformation_sigma: expected σ > 0 mm (or None), got {sigma}")
    else:
        fld, A, grp, s = (
            None,
            np.zeros((n_rows, 3, 0)),
            np.zeros(ms.n_models, np.int64),
            np.zeros(0),
        )
    rows = aux_sc = aux_tie = None
    if auxiliary:
        rows = auxiliary_rows(auxiliary, block)
        tie_of_pt = np.full(block.n_points, -1, np.int64)
        tie_of_pt[su.tie_points] = np.arange(su.tie_points.size)
        tie_of_img = np.full(block.n_images, -1, np.int64)
        tie_of_img[su.centre_images] = su.tie_points.size + np.arange(su.centre_images.size)
        aux_tie = np.full(rows.n, -1, np.int64)
        on = rows.on_image
        aux_tie[on] = tie_of_img[rows.target[on]]
        aux_tie[~on] = tie_of_pt[rows.target[~on]]
        if np.any(aux_tie < 0):
            bad = [rows.labels[i] for i in np.flatnonzero(aux_tie < 0)[:5]]
            raise InputError(
                "auxiliary data on points or centres that are in no model (or use_centres="
                f"False): {', '.join(bad)}"
            )
        aux_sc = su.scalar[aux_tie, rows.coord]
    return JointSetup(
        deformation, fld, A, grp, int(grp.max()) + 1, s, rows,
        aux_sc if aux_sc is not None else np.zeros(0, np.int64),
        aux_tie if aux_tie is not None else np.zeros(0, np.int64),
    )  # fmt: skip


def deformed(su, js: JointSetup, p: F64) -> F64:
    """Model coordinates of the rows with the current deformation, (k, 3) m."""
    if js.q == 0:
        return su.m
    return su.m - np.einsum(
        "nik,nk->ni", js.A, p.reshape(js.n_groups, js.q)[js.group[su.row_model]]
    )


def model_rows(su, js: JointSetup, lam, R, T, p):
    """Misclosures (k, 3), Jacobians by the 7 model parameters (k, 3, 7) and by the
    deformation parameters of the row's group (k, 3, q)."""
    j = su.row_model
    m = deformed(su, js, p)
    Rm = np.einsum("nij,nj->ni", R[j], m)
    r = lam[j, None] * Rm + T[j] - su.X[su.row_point]
    J = np.zeros((j.size, 3, 7))
    J[:, :, :3] = -lam[j, None, None] * (R[j] @ skew(m))
    J[:, :, 3] = Rm
    J[:, :, 4:] = np.eye(3)
    Jp = -lam[j, None, None] * (R[j] @ js.A)
    return r, J, Jp


def aux_residuals(su, js: JointSetup, g_aux: F64) -> F64:
    """Residuals (m) of the auxiliary rows at the current tie-point values."""
    if js.aux is None:
        return np.zeros(0)
    return js.aux.residuals(su.X[js.aux_tie, js.aux.coord], g_aux)


def _system(su, js: JointSetup, lam, R, T, p, g_aux, w_c):
    """Sparse Jacobians (rows × reduced unknowns, rows × scalars), weights, misclosures."""
    r, J, Jp = model_rows(su, js, lam, R, T, p)
    k, n = r.shape[0], su.n_models
    na = 7 * n + js.n_def + js.n_aux
    rows3 = np.arange(3 * k)
    cols7 = (np.repeat(su.row_model, 3)[:, None] * 7 + np.arange(7)).ravel()
    data, ri, ci = [J.reshape(-1)], [np.repeat(rows3, 7)], [cols7]
    if js.q:
        gcol = 7 * n + np.repeat(js.group[su.row_model], 3)[:, None] * js.q + np.arange(js.q)
        data.append(Jp.reshape(-1))
        ri.append(np.repeat(rows3, js.q))
        ci.append(gcol.ravel())
    sc = [su.scalar[su.row_point].ravel()]
    sgn = [-np.ones(3 * k)]
    w = [np.tile(w_c, k)]
    res = [r.ravel()]
    nrow = 3 * k
    if js.aux is not None and js.aux.n:
        a = js.aux
        Jg = a.jacobian_global()
        rr, cc = np.nonzero(Jg)
        data.append(Jg[rr, cc])
        ri.append(nrow + rr)
        ci.append(7 * n + js.n_def + cc)
        sc.append(js.aux_scalar)
        sgn.append(np.ones(a.n))
        w.append(a.w)
        res.append(aux_residuals(su, js, g_aux))
        nrow += a.n
    if js.q:  # pseudo-observations p = 0 ± σ of the deformation parameters
        pw = np.tile(1.0 / js.sigma**2, js.n_groups)
        keep = np.flatnonzero(pw > 0)
        data.append(np.ones(keep.size))
        ri.append(nrow + np.arange(keep.size))
        ci.append(7 * n + keep)
        sc.append(np.full(keep.size, -1, np.int64))
        sgn.append(np.zeros(keep.size))
        w.append(pw[keep])
        res.append(p[keep])
        nrow += keep.size
    Ja = sp.csr_matrix(
        (np.concatenate(data), (np.concatenate(ri), np.concatenate(ci))), shape=(nrow, na)
    )
    return Ja, np.concatenate(sc), np.concatenate(sgn), np.concatenate(w), np.concatenate(res)


class JointSteps:
    """The joint adjustment (models, deformation, auxiliary offsets) for the engine's loop.

    The iterate is (λ, R, T, p, g_aux) with the points ``su.X``; each Gauss-Newton step is
    applied in place (damping ``"none"``: every step is taken). See :mod:`._steps`.
    """

    def __init__(self, su, js: JointSetup, w_c: F64, s_xy: float, names: list[str]) -> None:
        self.su, self.js, self.w_c, self.s_xy, self.names = su, js, w_c, s_xy, names
        self.last = None

    def evaluate(self, state, jacobian: bool) -> Evaluation:
        lam, R, T, p, g_aux = state
        cost = joint_cost(self.su, self.js, lam, R, T, p, g_aux, self.w_c)
        return Evaluation(cost, True, None)

    def solve(self, state, ev: Evaluation, lam_damp: float, iteration: int) -> Step:
        su, js = self.su, self.js
        lam, R, T, p, g_aux = state
        n = su.n_models
        Ja, sc, sgn, w, r = _system(su, js, lam, R, T, p, g_aux, self.w_c)
        sol = solve_sparse(
            Ja, sc, sgn, w, r, su.n_scalar, prior_w=su.prior_w, prior_e=su.prior_e(),
            names=self.names, context="independent models",
        )  # fmt: skip
        da = sol.dtheta
        dt = da[: 7 * n].reshape(n, 7)
        R[:] = R @ matrix_from_rotvec(dt[:, :3])
        lam += dt[:, 3]
        T += dt[:, 4:]
        dp = da[7 * n : 7 * n + js.n_def]
        dg = da[7 * n + js.n_def :]
        p += dp
        g_aux += dg
        su.apply(sol.dX)
        self.last = sol
        size = max(
            float(np.max(np.abs(dt[:, :4]) * su.model_size[:, None], initial=0.0)),
            float(np.max(np.abs(dt[:, 4:]), initial=0.0)),
            float(np.max(np.abs(sol.dX), initial=0.0)),
            float(np.max(np.abs(dp), initial=0.0)) * 1e-3,
            float(np.max(np.abs(dg), initial=0.0)),
        )
        return Step(size / self.s_xy, None, (sol, size))

    def apply(self, state, step: Step):
        return state  # applied in place by solve

    def snapshot(self, state) -> F64:
        return np.empty(0)


def rigorous_joint(su, js, lam, R, T, w_c, s_xy, tol, max_iter, names):
    """Gauss-Newton of the joint adjustment; (converged, reason, sol, p, g_aux, history)."""
    p = np.zeros(js.n_def)
    g_aux = np.zeros(js.n_aux)
    steps = JointSteps(su, js, w_c, s_xy, names)
    run = iterate(
        steps, (lam, R, T, p, g_aux), redundancy=joint_redundancy(su, js), max_iter=max_iter,
        stop=stop_rule(tol * s_xy, f"corrections below {tol:g} σ_xy after {{iterations}}"),
    )  # fmt: skip
    return run.converged, run.reason, steps.last, p, g_aux, run.history


def joint_cost(su, js, lam, R, T, p, g_aux, w_c) -> float:
    r, _, _ = model_rows(su, js, lam, R, T, p)
    c = float(np.sum(r**2 * w_c) + np.sum(su.prior_w * su.prior_e() ** 2))
    if js.aux is not None:
        c += float(np.sum(js.aux.w * aux_residuals(su, js, g_aux) ** 2))
    if js.q:
        c += float(np.sum(p**2 / np.tile(js.sigma, js.n_groups) ** 2))
    return c


def joint_redundancy(su, js) -> int:
    n_pseudo = int(np.sum(np.isfinite(js.sigma))) * js.n_groups if js.q else 0
    n_aux_rows = js.aux.n if js.aux is not None else 0
    return su.redundancy + n_aux_rows + n_pseudo - js.n_def - js.n_aux


def explain_singular(exc: NotDeterminableError, retry) -> NotDeterminableError:
    """A NotDeterminableError naming the correlated deformation pairs of a regularised run.

    ``retry()`` runs the same adjustment with weak pseudo-observations (σ = 1000 mm) and
    returns its result (with ``deformation.analysis``).
    """
    try:
        trial = retry()
        an = trial.deformation.analysis
        pairs = ", ".join(f"{a}~{b} (ρ={r:+.3f})" for a, b, r in an.pairs[:6])
        pairs += (", " if pairs else "") + ", ".join(
            f"{a}~{b} (ρ={r:+.3f})" for a, b, r in an.with_exterior[:6]
        )
        und = ", ".join(an.undetermined[:6])
    except NotDeterminableError:
        pairs = und = ""
    msg = "the model deformation parameters are not determinable by this block"
    if pairs:
        msg += f"; correlated: {pairs}"
    if und:
        msg += f"; held only by the pseudo-observation: {und}"
    if not pairs and not und:
        msg += f" ({exc})"
    return NotDeterminableError(
        msg + "; give deformation_sigma or a smaller set", list(exc.parameters or [])
    )


def finish_joint(res: ModelsResult, block, ms, su, js, lam, R, T, p, g_aux, sol, names, w_c):
    """Add the extra unknowns, their precision and the analysis to a models result."""
    n = su.n_models
    n7 = 7 * n
    nx = res.x.size
    extra_x = np.concatenate([p, g_aux])
    res.x = np.concatenate([res.x, extra_x])
    res.names = list(res.names) + names[n7:]
    if js.n_def:
        res.groups["additional"] = slice(nx, nx + js.n_def)
    if js.n_aux:
        res.groups["auxiliary"] = slice(nx + js.n_def, nx + js.n_def + js.n_aux)
    cost = joint_cost(su, js, lam, R, T, p, g_aux, w_c)
    dof = joint_redundancy(su, js)
    res.redundancy = dof
    if res.adjusted is not None:  # + the extra rows (pseudo-observations, auxiliary) and unknowns
        n_pseudo = int(np.sum(np.isfinite(js.sigma))) * js.n_groups if js.q else 0
        n_rows = n_pseudo + (js.aux.n if js.aux is not None else 0)
        res.adjusted = (res.adjusted[0] + n_rows, res.adjusted[1] + js.n_def + js.n_aux)
    res.sigma0 = math.sqrt(cost / dof) if dof > 0 else float("nan")
    res.sigma0_m = res.sigma0 / math.sqrt(w_c[0])
    q_idx = np.arange(n7, n7 + js.n_def + js.n_aux)
    Q = sol.factor.solve(np.eye(sol.factor.scale.size)[:, q_idx]) if q_idx.size else None
    if js.n_def:
        qd = Q[:, : js.n_def]
        res.cofactor_groups["additional"] = qd[n7 : n7 + js.n_def]
        s = np.tile(js.sigma, js.n_groups)
        an = analyse(res, ap_sigma=js.sigma if np.all(np.isfinite(s)) else None)
        # correlations with the similarity parameters of the models
        dq = np.sqrt(np.clip(np.diag(res.cofactor_groups["additional"]), 1e-300, None))
        # correlations with the similarity parameters need diag(S⁻¹) of all models:
        # n7 / 256 solves, left out for very large blocks
        big = n7 > SIMILARITY_CHECK_LIMIT
        d7 = np.ones(n7) if big else np.sqrt(np.clip(_diag_inverse(sol, n7), 1e-300, None))
        C = qd[:n7] / np.outer(d7, dq)
        sim_names = res.names[:n7]
        for a in range(0 if big else js.n_def):
            jmax = int(np.argmax(np.abs(C[:, a])))
            if abs(C[jmax, a]) > an.threshold:
                an.with_exterior.append((an.names[a], sim_names[jmax], float(C[jmax, a])))
        if an.with_exterior:
            an.warnings.append(
                "not separable from the similarity: "
                + ", ".join(f"{a}~{b} (ρ={r:+.2f})" for a, b, r in an.with_exterior[:6])
            )
        res.deformation = DeformationEstimates(
            p.reshape(js.n_groups, js.q),
            res.sigma0 * dq.reshape(js.n_groups, js.q),
            an,
            js.group,
            js.deform,
        )
    if js.n_aux:
        qa = Q[n7 + js.n_def :, js.n_def :]
        res.cofactor_groups["auxiliary"] = qa
        res.auxiliary = AuxiliaryEstimates(
            js.aux.split_globals(g_aux),
            js.aux.split_globals(res.sigma0 * np.sqrt(np.diag(qa))),
            aux_residuals(su, js, g_aux),
            js.aux.labels,
            list(js.aux.names),
        )
    # check points: transform their deformed model coordinates
    if js.q:
        fld = js.field
        A = fld.evaluate(ms.xyz, ms.point_model)
        ms_d = dataclasses.replace(
            ms,
            xyz=ms.xyz
            - np.einsum("nik,nk->ni", A, p.reshape(js.n_groups, js.q)[js.group[ms.point_model]]),
        )
        xyz, _ = su.block_coordinates(block, ms_d, lam, R, T)
        res.points = xyz
        res.check_points = check_points_of(block, xyz)
    return res


def _diag_inverse(sol, n7: int, chunk: int = 256) -> F64:
    """Diagonal of S⁻¹ for the first n7 reduced unknowns."""
    out = np.empty(n7)
    size = sol.factor.scale.size
    for s0 in range(0, n7, chunk):
        idx = np.arange(s0, min(n7, s0 + chunk))
        E = np.zeros((size, idx.size))
        E[idx, np.arange(idx.size)] = 1.0
        out[idx] = sol.factor.solve(E)[idx, np.arange(idx.size)]
    return out


def point_cofactors(sol, su):
    """3 × 3 cofactor blocks of the tie points and centres."""
    return scalar_cofactors(sol, su.scalar)
