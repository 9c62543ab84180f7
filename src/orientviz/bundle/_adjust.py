"""Bundle block adjustment: all image bundles of a block at once (collinearity).

Every image ray ``x_obs + v = project(X, X0, R(ω, φ, κ), c, x0, y0) + A(x_obs)·a`` (see
:mod:`orientviz.camera`: image plane at z = −c, mm; R image → object with the block's
rotation sequence, ``"opk"`` R = R_ω R_φ R_κ or ``"pok"`` R = R_φ R_ω R_κ) is one
observation equation; the unknowns are the exterior orientations (X0, Y0, Z0 in m,
ω, φ, κ in rad), the object points (m) and optional additional parameters ``a`` of
self-calibration shared by groups of images. Control coordinates are fixed or
weighted pseudo-observations, observed projection centres/attitudes
(``images.X0_obs``/``X0_sigma``, ``angles_obs``/``angles_sigma``) weighted ones.

Solution: Gauss-Newton on the normal equations with the points eliminated by the Schur
complement (:mod:`orientviz.bundle._reduced`), a Levenberg-Marquardt fallback when a step
would increase vᵀPv, and a parameter-based stopping rule: stop when every correction
is below ``tol`` times the parameter's a-priori (conditional) σ = 1/√N_ii. The cost
alone is a poor criterion in large blocks: their weak bending modes barely change it.

Convergence range (measured on the peer bench's 200-image block, 10 × 20, perimeter
control): from start errors of 5 m / 1 gon / 5 m (positions / angles / points) 4
iterations; from 100 m / 10 gon / 100 m 8 iterations, same optimum; from 200 m / 20 gon
/ 200 m the normal matrix at the start is not even positive definite — damped steps are
tried, and the result reports ``converged=False`` with a reason that points to
:func:`orientviz.block.approximate_values`, after which the bundle converges
in 3 iterations. (The peers — pycolmap, GTSAM, Ceres, SciPy — diverge there too.)

Self-calibration (``additional=``): the parameters border the reduced system
(:mod:`orientviz.bundle._ap_normal` assembles E, F; :mod:`orientviz.bundle._border`
solves). From poor approximations (start σ0 ≥ :data:`POOR_START_SIGMA0`) the first step
holds the parameters at their values: they model image errors of a few µm and should not
absorb the errors of the approximations. E and F are reused in the next iteration when
the last step moved nothing by more than :data:`AP_REUSE` of the ray length (the
Jacobians then change by less than the tolerance of the border's solve). On the bench's
2 100-image block with 12 parameters per strip (q = 360) the self-calibrating bundle
takes the same 4 iterations as the plain one, in about 1.25 times its time (best of 7,
1.23-1.34 median at load 1-2; ``python benchmarks/bench_selfcal.py``); with
``precision=True`` the cofactors add about 1.25-1.4 times a plain bundle's time on top
(:mod:`orientviz.bundle._precision_ap`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..adjust.result import Adjustment, Iteration
from ..block import Block
from ..errors import NotDeterminableError
from ._ap_normal import NormalEquations, ap_normal, point_ap_term, setup_additional
from ._border import solve_border
from ._checks import check_connected, check_datum, check_determinable, point_setup
from ._kernel import collinearity_block, project_block
from ._reduced import ReducedStructure, assemble_blocks, factor_reduced, inv3

F64 = NDArray[np.float64]
EXTERIOR_NAMES = ("X0", "Y0", "Z0", "omega", "phi", "kappa")
#: Blocks up to this many images keep the full parameter vector in every history record.
HISTORY_X_LIMIT: int = 500
#: Above this start σ0 a singular first normal matrix is blamed on the approximations
#: (damped steps are tried) rather than reported as a defect at once.
POOR_START_SIGMA0: float = 30.0
#: The border E, F of the additional parameters is reused in the next iteration when the
#: last step moved no projection centre or point by more than this fraction of the
#: median ray length and no angle by more than this (rad): the Jacobians then change by
#: about as little (1e-4 relative), less than the tolerance of the border's solve.
AP_REUSE: float = 1e-4


@dataclass
class _State:
    X0: F64
    angles: F64
    xyz: F64  # all points (p, 3)
    ap: F64  # (q,)
    g: F64 | None = None  # offsets/drifts of auxiliary data (auxiliary_obs)


def _wrap(a: F64) -> F64:
    return (a + np.pi) % (2 * np.pi) - np.pi


class BundleProblem:
    """The constant part of a bundle adjustment: indices, weights, structure.

    Built by :func:`bundle_adjust`; exposed so that benchmarks and the precision module
    can reuse it. Not part of the stable API.
    """

    def __init__(
        self, block, setup, *, additional=None, ap_group=None, ap_sigma=None, solver="banded",
        auxiliary=None,
    ):  # fmt: skip
        self.block = block
        self.setup = setup
        img, obs = block.images, block.observations
        m = block.n_images
        self.m = m
        self.uobs = np.flatnonzero(setup.used_obs)
        self.oi = obs.image[self.uobs]
        self.opt = obs.point[self.uobs]
        self.l = obs.xy[self.uobs]
        self.sw = 1.0 / obs.sigma[self.uobs]
        cam = img.camera
        cams = block.cameras
        self.c, self.x0, self.y0 = cams.c[cam], cams.x0[cam], cams.y0[cam]
        self.var_pts = np.flatnonzero(setup.unknown)
        self.pt_col = -np.ones(block.n_points, np.int64)
        self.pt_col[self.var_pts] = np.arange(self.var_pts.size)
        # observations in point order (fixed points last): the point reductions then
        # work on contiguous slices, without gathers
        col = self.pt_col[self.opt]
        order = np.lexsort((self.oi, np.where(col >= 0, col, np.iinfo(np.int64).max)))
        self.uobs = self.uobs[order]
        self.oi, self.opt = self.oi[order], self.opt[order]
        self.l, self.sw = self.l[order], self.sw[order]
        self.ocol = col[order]
        self.struct = ReducedStructure(
            self.oi,
            self.ocol,
            m,
            self.var_pts.size,
            solver=solver,
            positions=img.X0 if solver == "banded" else None,
        )
        nv = int(np.sum(self.ocol >= 0))
        pv = self.struct.pt_obs
        self.vo = slice(0, nv) if np.array_equal(pv, np.arange(nv)) else pv
        # pseudo-observations of points
        ps = setup.prior_sigma[self.var_pts]
        self.prior_w = np.where(np.isfinite(ps), 1.0 / ps**2, 0.0)
        self.prior_l = np.nan_to_num(setup.known[self.var_pts])

        # observed exterior orientation
        def _eo_w(o, s):
            ok = np.isfinite(o) & np.isfinite(s) & (s > 0)
            return np.where(ok, 1.0 / np.where(ok, s, 1.0) ** 2, 0.0), np.nan_to_num(o)

        self.X0_w, self.X0_l = _eo_w(img.X0_obs, img.X0_sigma)
        self.ang_w, self.ang_l = _eo_w(img.angles_obs, img.angles_sigma)
        # additional parameters (k per group, G groups): see bundle_ap.setup_additional
        setup_additional(self, additional, ap_group, ap_sigma)
        self.q = self.k * self.G
        # auxiliary data as joint observations: hook of orientviz.bundle._auxiliary
        self.aux, self.na = None, 0
        if auxiliary:
            from ._auxiliary import BundleAuxiliary, auxiliary_rows

            self.aux = BundleAuxiliary(auxiliary_rows(auxiliary, block), self.pt_col)
            self.na = self.aux.n_global
        n_pseudo = int((self.prior_w > 0).sum() + (self.X0_w > 0).sum() + (self.ang_w > 0).sum())
        n_pseudo += int((self.ap_w > 0).sum()) if self.q else 0
        self.n_eq = 2 * self.uobs.size + n_pseudo + (self.aux.rows.n if self.aux else 0)
        self.n_unknowns = 6 * m + 3 * self.var_pts.size + self.q + self.na
        self.redundancy = self.n_eq - self.n_unknowns

    # ----------------------------------------------------------------- model
    def residuals(self, st: _State, jac: bool):
        """Weighted misclosures l − f (n, 2)·(1/σ), with Jacobians if ``jac``."""
        xyz = st.xyz[self.opt]
        seq = self.block.sequence
        if jac:
            f, Je, Jp = collinearity_block(
                st.X0, st.angles, self.c, self.x0, self.y0, self.oi, xyz, seq
            )
        else:
            f = project_block(st.X0, st.angles, self.c, self.x0, self.y0, self.oi, xyz, seq)
            Je = Jp = None
        if self.q:
            f = f + (self.A_csr @ st.ap).reshape(-1, 2)
        return (self.l - f) * self.sw, Je, Jp

    def cost(self, st: _State, rw: F64) -> float:
        c = float(np.sum(rw**2))
        d = self.prior_l - st.xyz[self.var_pts]
        c += float(np.sum(self.prior_w * d**2))
        c += float(np.sum(self.X0_w * (self.X0_l - st.X0) ** 2))
        c += float(np.sum(self.ang_w * _wrap(self.ang_l - st.angles) ** 2))
        if self.q:
            c += float(np.sum(self.ap_w * st.ap**2))
        if self.aux:
            c += self.aux.cost(st.X0, st.xyz, st.g)
        return c

    # ----------------------------------------------------------------- normal equations
    def normal(self, st: _State, rw: F64, Je: F64, Jp: F64, lam: float = 0.0) -> dict:
        """Blocks of the normal equations and the Schur complement (see bundle._reduced)."""
        S = self.struct
        sw = self.sw[:, :, None]
        Jew, Jpw = Je * sw, Jp * sw
        # image blocks: gather the (n, 2, 6) Jacobian by image, then reduce
        Jc = Jew[S.cam_order]
        JcT = Jc.transpose(0, 2, 1)
        U = np.zeros((self.m, 6, 6))
        U[S.cam_present] = np.add.reduceat(JcT @ Jc, S.cam_starts, axis=0)
        bc = np.zeros((self.m, 6))
        bc[S.cam_present] = np.add.reduceat(
            np.einsum("nki,nk->ni", Jc, rw[S.cam_order]), S.cam_starts, axis=0
        )
        del Jc, JcT
        U[:, [0, 1, 2], [0, 1, 2]] += self.X0_w
        bc[:, :3] += self.X0_w * (self.X0_l - st.X0)
        U[:, [3, 4, 5], [3, 4, 5]] += self.ang_w
        bc[:, 3:] += self.ang_w * _wrap(self.ang_l - st.angles)
        if self.aux:
            self.aux.add_images(U, bc, st.X0, st.xyz, st.g)
        vo = self.vo
        Jpv = Jpw[vo]
        V = np.add.reduceat(Jpv.transpose(0, 2, 1) @ Jpv, S.pt_starts, axis=0)
        bp = np.add.reduceat(np.einsum("nki,nk->ni", Jpv, rw[vo]), S.pt_starts, axis=0)
        i3 = [0, 1, 2]
        V[:, i3, i3] += self.prior_w
        bp += self.prior_w * (self.prior_l - st.xyz[self.var_pts])
        if self.aux:
            self.aux.add_points(V, bp, st.X0, st.xyz, st.g)
        diagU = U[:, range(6), range(6)].copy()
        diagV = V[:, i3, i3].copy()
        if lam > 0:
            U[:, range(6), range(6)] *= 1.0 + lam
            V[:, i3, i3] *= 1.0 + lam
        Vinv = inv3(V)
        W = np.zeros((Je.shape[0], 6, 3))
        W[vo] = Jew[vo].transpose(0, 2, 1) @ Jpv
        T = np.zeros_like(W)
        T[vo] = W[vo] @ Vinv[self.ocol[vo]]
        blocks = assemble_blocks(S, U, T, W)
        Tb = np.zeros((Je.shape[0], 6))
        Tb[vo] = np.einsum("nij,nj->ni", T[vo], bp[self.ocol[vo]])
        red = bc.copy()
        red[S.cam_present] -= np.add.reduceat(Tb[S.cam_order], S.cam_starts, axis=0)
        out = NormalEquations(
            blocks=blocks, rhs=red.reshape(-1), Vinv=Vinv, W=W, T=T, bp=bp, diagU=diagU, diagV=diagV
        )
        if self.q:
            if self.ap_hold:
                out["diagF"] = np.ones(self.q)
            else:
                border = self.ap_border if self.ap_reuse else None
                out.update(ap_normal(self, st, rw, Jew, Jpw, T, Vinv, bp, lam, border))
                out["E_border"] = out.pop("E")  # blocks; out["E"] forms the array on demand
                self.ap_border = (out["E_border"], out["F0"])
                out["reused"] = border is not None
        if self.aux:
            self.aux.normal(self, st, out, lam)
        return out

    def solve(self, ne: dict, names: list[str]):
        """Corrections (dc (m, 6), dp (p_var, 3), da (q,)) and the factor of S."""
        fac = factor_reduced(self.struct, ne["blocks"], names)
        if self.aux:
            return self.aux.solve(self, fac, ne)
        if self.q:
            dc, da = solve_border(self, ne, fac)
        else:
            dc = fac.solve(ne["rhs"])
            da = np.zeros(0)
        return self._back(ne, dc, da, fac)

    def _back(self, ne: dict, dc: F64, da: F64, fac):
        """Back-substitution of the points; returns (dc, dp, da, fac)."""
        dc = dc.reshape(self.m, 6)
        S = self.struct
        vo = S.pt_obs
        t = np.einsum("nji,nj->ni", ne["W"][vo], dc[self.oi[vo]])
        red = ne["bp"] - np.add.reduceat(t, S.pt_starts, axis=0)
        if self.q and not self.ap_hold:
            red -= point_ap_term(self, ne["H"], da)
        dp = np.einsum("nij,nj->ni", ne["Vinv"], red)
        return dc, dp, da, fac

    def apply(self, st: _State, dc: F64, dp: F64, da: F64) -> _State:
        xyz = st.xyz.copy()
        xyz[self.var_pts] += dp
        if self.aux:  # da: the additional parameters, then the auxiliary offsets/drifts
            q = self.q
            return _State(
                st.X0 + dc[:, :3], st.angles + dc[:, 3:], xyz, st.ap + da[:q], st.g + da[q:]
            )
        return _State(st.X0 + dc[:, :3], st.angles + dc[:, 3:], xyz, st.ap + da, st.g)

    def names(self) -> list[str]:
        b = self.block
        out = [f"{i}.{n}" for i in b.images.ids for n in EXTERIOR_NAMES]
        out += [f"{i}.{c}" for i in b.points.ids for c in ("X", "Y", "Z")]
        return out + (list(self.ap_names) if self.q else [])

    def flat(self, st: _State) -> F64:
        return np.concatenate([np.hstack([st.X0, st.angles]).ravel(), st.xyz.ravel(), st.ap])


def bundle_adjust(
    block: Block,
    *,
    control: str = "fixed",
    max_iter: int = 30,
    tol: float = 5e-3,
    additional=None,
    ap_group=None,
    ap_sigma=None,
    precision: bool = True,
    callback: Callable[[Iteration], object] | None = None,
    solver: str = "banded",
    history_x: bool | None = None,
    auxiliary: list | None = None,
) -> Adjustment:
    """Adjust a block by the bundle method (see module docstring for the model).

    Parameters
    ----------
    block : Block
        Approximate values in ``images.X0``/``angles`` (rad, ``block.sequence``) and
        ``points.xyz`` (m); see :func:`orientviz.block.approximate_values`.
    control : {"fixed", "weighted"}
        ``"fixed"``: every given coordinate of a control point is held fixed.
        ``"weighted"``: given coordinates with ``points.sigma`` > 0 are observations
        with that σ (m), σ = 0 still fixes. Check points (role 2) are left out and
        intersected afterwards with the adjusted orientations.
    max_iter : int
        Maximum number of Gauss-Newton steps.
    tol : float
        Stop when every ‖correction‖ < tol · (a-priori conditional σ = 1/√N_ii). The
        conditional σ is much smaller than the real one in a block, so the rule is
        strict: with 5e-3 the bench blocks stop within 0.001 mm of the optimum.
    additional : AdditionalParameters, optional
        Self-calibration set (``design(xy) -> (n, 2, k)`` in mm per unit, evaluated at the
        observed coordinates): ``x_obs + v = project(...) + A(x_obs)·a``.
    ap_group : array_like of int, shape (m,), optional
        Group of each image for the additional parameters (default: one group).
    ap_sigma : float or array_like (k,), optional
        σ of the pseudo-observations a = 0 (units of the parameters); None = free.
    precision : bool
        Compute per-image 6×6 and per-point 3×3 cofactor blocks, redundancy numbers and
        normalised residuals (:mod:`orientviz.bundle._precision`).
    callback : callable, optional
        Called with each new :class:`Iteration`.
    solver : {"banded", "splu", "dense"}
        Solver of the reduced camera system (:mod:`orientviz.bundle._reduced`).
    history_x : bool, optional
        Keep the full parameter vector per iteration (default: blocks ≤ 500 images);
        otherwise ``Iteration.x`` is empty.
    auxiliary : list of Auxiliary, optional
        GNSS / statoscope / APR data as joint observations with offset/drift unknowns
        per strip (:mod:`orientviz.bundle._auxiliary`), also together with
        ``additional`` (both border the reduced system:
        :mod:`orientviz.bundle._auxiliary_border`). Estimates in ``extra["auxiliary"]``,
        ``"auxiliary_sigma"`` (m), ``cofactor_blocks["auxiliary"]``; the rows are
        appended to the observations (``extra["obs_slices"]["auxiliary"]``, m; also
        ``extra["auxiliary_residuals"]``) and with ``precision`` get redundancy numbers
        and normalised residuals; the cofactor blocks of orientations and points then
        include the uncertainty of the offsets/drifts. The datum check is left to the
        normal equations.

    Returns
    -------
    Adjustment
        Blocks ``"exterior"`` ((m, 6): X0, Y0, Z0 m, ω, φ, κ rad), ``"points"`` ((p, 3) m;
        fixed control at its given value, check points intersected) and
        ``"additional"``; residuals v = f − l: the 2n image coordinates (x, y per
        observation, mm) first, then the pseudo-observations. ``extra`` holds
        ``check_rms`` (m, X/Y/Z), ``check_points``, ``used_obs``, ``solver``.
    """
    setup = point_setup(block, control)
    check_connected(block, setup)
    check_determinable(block, setup)
    if not auxiliary:
        check_datum(block, setup)
    prob = BundleProblem(
        block, setup, additional=additional, ap_group=ap_group, ap_sigma=ap_sigma, solver=solver,
        auxiliary=auxiliary,
    )  # fmt: skip
    names = prob.names()
    red_names = names[: 6 * prob.m]
    xyz0 = block.points.xyz.copy()
    fixed = setup.fixed
    xyz0[fixed] = np.where(np.isfinite(setup.known[fixed]), setup.known[fixed], xyz0[fixed])
    st = _State(
        block.images.X0.copy(), block.images.angles.copy(), xyz0, np.zeros(prob.q),
        np.zeros(prob.na),
    )  # fmt: skip
    keep_x = (block.n_images <= HISTORY_X_LIMIT) if history_x is None else bool(history_x)
    dof = prob.redundancy

    def s0(c):
        return float(np.sqrt(c / dof)) if dof > 0 else float("nan")

    rw, Je, Jp = prob.residuals(st, jac=True)
    cost = prob.cost(st, rw)
    history = [Iteration(0, prob.flat(st) if keep_x else np.empty(0), None, s0(cost), cost)]
    lam, converged, damped_start = 0.0, False, False
    reason = f"reached the maximum of {max_iter} iterations"
    # additional parameters model image errors of a few µm: from approximations whose
    # misclosures are far larger (σ0 ≥ POOR_START_SIGMA0) the first step is taken with
    # the parameters held at their values — it costs no border, and the parameters do
    # not absorb errors of the approximations (the first joint step then starts close)
    hold_first = bool(prob.q) and history[0].sigma0 >= POOR_START_SIGMA0
    first = 2 if hold_first else 1  # the first iteration that solves the full system
    lin = None  # (normal equations, factor, Jacobians) of the last plain undamped step
    for it in range(1, max_iter + 1):
        prob.ap_hold = hold_first and it == 1
        lin = None  # released before the next normal equations are built
        while True:
            ne = prob.normal(st, rw, Je, Jp, lam)
            try:
                dc, dp, da, fac = prob.solve(ne, red_names)
            except NotDeterminableError:
                # at a good start a singular S is a real defect; at a poor start (σ0 ≫ 1)
                # it may be an artefact of the approximations: try damped steps, and
                # verify the undamped system at the solution (below)
                if it == first and lam == 0 and history[-1].sigma0 < POOR_START_SIGMA0:
                    raise
                damped_start = damped_start or it <= first
                lam = max(10 * lam, 1e-3)
                if lam > 1e8:
                    reason = f"the normal equations stayed singular in iteration {it}"
                    break
                continue
            new = prob.apply(st, dc, dp, da)
            # derivatives at the new state: for the next iteration, the precision or
            # the check of a damped start (not after the last step of a screening run)
            need = it < max_iter or precision or damped_start or prob.aux is not None
            rw_n, Je_n, Jp_n = prob.residuals(new, jac=need)
            c_new = prob.cost(new, rw_n)
            if np.isfinite(c_new) and c_new <= cost * (1 + 1e-12) + 1e-12:
                break
            lam = max(10 * lam, 1e-4)
            if lam > 1e8:
                reason = f"no step decreases vᵀPv in iteration {it} (damping exhausted)"
                break
        if lam > 1e8:
            break
        # parameter-based stopping: corrections in units of the conditional σ
        rel = max(
            float(np.max(np.abs(dc) * np.sqrt(ne["diagU"]), initial=0.0)),
            float(np.max(np.abs(dp) * np.sqrt(ne["diagV"]), initial=0.0)),
            float(np.max(np.abs(da) * np.sqrt(ne["diagF"]), initial=0.0))
            if prob.q or prob.na
            else 0.0,
        )
        dx = None
        if keep_x:  # same layout as x: zeros for fixed points
            dpa = np.zeros((block.n_points, 3))
            dpa[prob.var_pts] = dp
            dx = np.concatenate([dc.ravel(), dpa.ravel(), da[: prob.q]])
        # the precision may reuse this linearisation when it is the converged one
        if precision and lam == 0 and not (prob.q or prob.aux):
            lin = (ne, fac, Je, Jp)
        st, rw, Je, Jp, cost = new, rw_n, Je_n, Jp_n, c_new
        if prob.q:
            L = AP_REUSE * prob.ray_length
            prob.ap_reuse = (
                not prob.ap_hold
                and float(np.max(np.abs(dc[:, :3]), initial=0.0)) < L
                and float(np.max(np.abs(dc[:, 3:]), initial=0.0)) < AP_REUSE
                and float(np.max(np.abs(dp), initial=0.0)) < L
            )
        rec = Iteration(it, prob.flat(st) if keep_x else np.empty(0), dx, s0(cost), cost, lam, rel)
        history.append(rec)
        if callback is not None:
            callback(rec)
        lam = lam / 10 if lam > 1e-6 else 0.0
        if rel < tol and not prob.ap_hold:
            converged, reason = True, f"corrections below {tol:g} σ after {it} iterations"
            break
    prob.ap_hold = prob.ap_reuse = False
    if not converged:
        lin = None
    if damped_start:  # a start that needed damping: prove the solution is determinable
        try:
            prob.solve(prob.normal(st, rw, Je, Jp), red_names)
        except NotDeterminableError:
            converged, precision = False, False
            reason = (
                f"no convergence from poor approximate values (start σ0 = {history[0].sigma0:.3g}): "
                "the normal equations are not positive definite there; compute better "
                "approximations, e.g. with orientviz.block.approximate_values"
            )
    res = _finish(
        block,
        prob,
        st,
        rw,
        Je,
        Jp,
        cost,
        names,
        history,
        converged,
        reason,
        precision,
        dof,
        s0(cost),
        lin,
    )
    if prob.aux:
        from ._auxiliary import finish_bundle

        finish_bundle(res, prob, st, rw, Je, Jp)
    return res


def _finish(
    block, prob, st, rw, Je, Jp, cost, names, history, converged, reason, precision, dof, sigma0,
    lin=None,
):  # fmt: skip
    from ._result import finish_result

    return finish_result(
        block, prob, st, rw, Je, Jp, names, history, converged, reason, precision, dof, sigma0,
        lin=lin,
    )  # fmt: skip
