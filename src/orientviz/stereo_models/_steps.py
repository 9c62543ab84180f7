"""The independent-model adjustments as problems of the engine's one loop.

:func:`orientviz.adjust.iterate` runs them (pure Gauss-Newton, damping ``"none"``); this
module says what one step is:

* :class:`RigorousSteps` — all 7 parameters of every model and the point coordinates in
  one linearised system (the points eliminated, :mod:`._normal`);
* :class:`PatmSteps` — one PAT-M alternation: the planimetric 4-parameter step, then the
  height step linearised at the planimetric result.

The iterate is the models' λ (n,), R (n, 3, 3), T (n, 3) together with the point
coordinates ``su.X`` of the :class:`~._setup.TieSetup`; steps are applied in place (every
Gauss-Newton step is taken, so no earlier iterate is needed again). vᵀPv is that of the
rigorous model (:func:`rows3`) for both methods. A step's size is the largest
correction in m (rotations and scale times the model size); the loop stops when it is
below ``tol`` × σ_xy (``Step.max_correction`` is that size in σ_xy).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..adjust import Evaluation, Step, StopRule
from ..rotation import matrix_from_opk, matrix_from_rotvec, opk_from_matrix, skew
from ._normal import solve_rows
from ._setup import TieSetup

F64 = NDArray[np.float64]


def rows3(su: TieSetup, lam: F64, R: F64, T: F64):
    """Misclosures (k, 3) and Jacobians (k, 3, 7) of all used model points."""
    j, m = su.row_model, su.m
    Rm = np.einsum("nij,nj->ni", R[j], m)
    f = lam[j, None] * Rm + T[j]
    r = f - su.X[su.row_point]
    J = np.zeros((j.size, 3, 7))
    J[:, :, :3] = -lam[j, None, None] * (R[j] @ skew(m))
    J[:, :, 3] = Rm
    J[:, :, 4:] = np.eye(3)
    return r, J


def model_params(lam: F64, R: F64, T: F64) -> F64:
    """X0 Y0 Z0 ω φ κ λ per model, (n, 7)."""
    om, ph, ka = opk_from_matrix(R)
    return np.column_stack([T, om, ph, ka, lam])


def stop_rule(limit: float, reason: str) -> StopRule:
    """Stop when the step's largest correction is below ``limit`` (m; ``tol`` × σ_xy)."""
    return StopRule(step_test=lambda step: step.data[1] < limit, step_reason=reason)


class _ModelSteps:
    """What both methods share: vᵀPv of the rigorous model and the snapshot."""

    def __init__(self, su: TieSetup, w_c: F64, s_xy: float) -> None:
        self.su, self.w_c, self.s_xy = su, w_c, s_xy
        self.last = None  # the last solution of the normal equations (for the precision)

    def evaluate(self, state, jacobian: bool) -> Evaluation:
        r, J = rows3(self.su, *state)
        cost = float(np.sum(r**2 * self.w_c) + np.sum(self.su.prior_w * self.su.prior_e() ** 2))
        return Evaluation(cost, True, (r, J))

    def apply(self, state, step: Step):
        return state  # the step was applied in place by solve

    def snapshot(self, state) -> F64:
        return np.concatenate([model_params(*state).ravel(), self.su.X.ravel()])

    def _step(self, size: float) -> Step:
        return Step(size / self.s_xy, None, (self.last, size))


class RigorousSteps(_ModelSteps):
    """One Gauss-Newton step of the rigorous adjustment (7 parameters per model)."""

    def solve(self, state, ev: Evaluation, lam_damp: float, iteration: int) -> Step:
        su = self.su
        lam, R, T = state
        r, J = ev.data
        k = r.shape[0]
        sol = solve_rows(
            np.repeat(su.row_model, 3), J.reshape(3 * k, 7), su.scalar[su.row_point].ravel(),
            np.tile(self.w_c, k), r.ravel(), su.n_models, su.n_scalar, prior_w=su.prior_w,
            prior_e=su.prior_e(), names=su.param_names(7), context="independent models",
        )  # fmt: skip
        dt = sol.dtheta
        R[:] = R @ matrix_from_rotvec(dt[:, :3])
        lam += dt[:, 3]
        T += dt[:, 4:]
        su.apply(sol.dX)
        size = su.model_size
        self.last = sol
        return self._step(
            max(
                float(np.max(np.abs(dt[:, :4]) * size[:, None], initial=0.0)),
                float(np.max(np.abs(dt[:, 4:]), initial=0.0)),
                float(np.max(np.abs(sol.dX), initial=0.0)),
            )
        )


class PatmSteps(_ModelSteps):
    """One PAT-M alternation: planimetry (a, b, tx, ty), then height (dz, ω, φ)."""

    def solve(self, state, ev: Evaluation, lam_damp: float, iteration: int) -> Step:
        su, w_c = self.su, self.w_c
        lam, R, T = state
        j = su.row_model
        P = lam[j, None] * np.einsum("nij,nj->ni", R[j], su.m) + T[j]
        k = P.shape[0]
        # --- planimetry: X = a·Px − b·Py + tx, Y = b·Px + a·Py + ty (exactly linear)
        J = np.zeros((k, 2, 4))
        J[:, 0] = np.column_stack([P[:, 0], -P[:, 1], np.ones(k), np.zeros(k)])
        J[:, 1] = np.column_stack([P[:, 1], P[:, 0], np.zeros(k), np.ones(k)])
        r = P[:, :2] - su.X[su.row_point, :2]
        g = su.row_point < su.tie_points.size  # the projection centres tie heights only
        sub, n_sub, sel = su.sub((0, 1), rows=g)
        solp = solve_rows(
            np.repeat(j[g], 2), J[g].reshape(-1, 4), sub[su.row_point[g]].ravel(),
            np.tile(w_c[:2], int(g.sum())), r[g].ravel(), su.n_models, n_sub,
            prior_w=su.prior_w[sel], prior_e=su.prior_e()[sel],
            names=su.param_names(4, ("a", "b", "tx", "ty")), context="independent models (planimetry)",
        )  # fmt: skip
        a = 1.0 + solp.dtheta[:, 0]
        b, tx, ty = solp.dtheta[:, 1], solp.dtheta[:, 2], solp.dtheta[:, 3]
        s = np.hypot(a, b)
        Rz = matrix_from_opk(0.0 * s, 0.0 * s, np.arctan2(b, a))
        zc = su.model_mean_z(lam, R, T)
        t3 = np.column_stack([tx, ty, (1.0 - s) * zc])
        lam *= s
        R[:] = Rz @ R
        T[:] = s[:, None] * np.einsum("nij,nj->ni", Rz, T) + t3
        step_xy = np.abs(solp.dX).max(initial=0.0)
        dX = np.zeros(su.n_scalar)
        dX[sel] = solp.dX
        su.apply(dX, coords=(0, 1))
        # --- height: Z = Pz + dz + ω (Py − cy) − φ (Px − cx)
        P = lam[j, None] * np.einsum("nij,nj->ni", R[j], su.m) + T[j]
        cen = su.model_centre(P)
        d = P - cen[j]
        Jh = np.column_stack([np.ones(k), d[:, 1], -d[:, 0]])
        rh = P[:, 2] - su.X[su.row_point, 2]
        zsub, nz, zsel = su.sub((2,))
        rs, wh, j_h = zsub[su.row_point][:, 0], np.full(k, w_c[2]), j
        pc = ~g
        sel = zsel
        if np.any(pc):
            # the tilts move the projection centres sideways: x' = x + φ·Δz, y' = y − ω·Δz;
            # their X, Y are unknowns of the height step, shared by consecutive models
            xysub, nxy, xysel = su.sub((0, 1), rows=pc)
            q, dzq = np.flatnonzero(pc), d[pc, 2]
            zero = np.zeros(q.size)
            Jh = np.vstack(
                [Jh, np.column_stack([zero, zero, dzq]), np.column_stack([zero, -dzq, zero])]
            )
            rh = np.concatenate(
                [rh, P[q, 0] - su.X[su.row_point[q], 0], P[q, 1] - su.X[su.row_point[q], 1]]
            )
            rs = np.concatenate(
                [rs, xysub[su.row_point[q], 0] + nz, xysub[su.row_point[q], 1] + nz]
            )
            wh = np.concatenate([wh, np.full(2 * q.size, w_c[0])])
            j_h = np.concatenate([j, j[q], j[q]])
            sel = np.concatenate([zsel, xysel])
            nz += nxy
        solh = solve_rows(
            j_h, Jh, rs, wh, rh, su.n_models, nz,
            prior_w=su.prior_w[sel], prior_e=su.prior_e()[sel],
            names=su.param_names(3, ("dz", "omega", "phi")),
            context="independent models (height)",
        )  # fmt: skip
        dz, om, ph = solh.dtheta.T
        Rt = matrix_from_opk(om, ph, 0.0 * om)
        T[:] = np.einsum("nij,nj->ni", Rt, T - cen) + cen + np.column_stack([0 * dz, 0 * dz, dz])
        R[:] = Rt @ R
        dX = np.zeros(su.n_scalar)
        dX[sel] = solh.dX
        su.apply(dX, coords=(0, 1, 2) if np.any(pc) else (2,))
        self.last = solh
        return self._step(
            max(
                step_xy,
                float(np.abs(solh.dX).max(initial=0.0)),
                float(np.max(np.abs(s - 1.0) * su.model_size, initial=0.0)),
                float(np.max(np.abs(solh.dtheta[:, 1:]) * su.model_size[:, None], initial=0.0)),
                float(np.abs(solh.dtheta[:, 0]).max(initial=0.0)),
            )
        )
