"""Bundle block adjustment: all image bundles of a block at once (collinearity).

Every image ray ``x_obs + v = project(X, X0, R(ω, φ, κ), c, x0, y0) + A(x_obs)·a`` (see
:mod:`orientviz.camera`: image plane at z = −c, mm; R image → object with the block's
rotation sequence, ``"opk"`` R = R_ω R_φ R_κ or ``"pok"`` R = R_φ R_ω R_κ) is one
observation equation; the unknowns are the exterior orientations (X0, Y0, Z0 in m,
ω, φ, κ in rad), the object points (m) and optional additional parameters ``a`` of
self-calibration shared by groups of images. Control coordinates are fixed or
weighted pseudo-observations, observed projection centres/attitudes
(``images.X0_obs``/``X0_sigma``, ``angles_obs``/``angles_sigma``) weighted ones.

:func:`bundle_adjust` checks the datum and determinability
(:mod:`orientviz.bundle.problem._checks`), builds the
:class:`~orientviz.bundle.problem.BundleProblem`, and runs the engine's loop
(:func:`orientviz.adjust.loop.iterate`) over its steps
(:class:`~orientviz.bundle.loop._steps.BundleSteps`): Gauss-Newton on the normal
equations with the points eliminated (:mod:`orientviz.bundle.reduced`), a
Levenberg-Marquardt fallback when a step would increase vᵀPv, and a parameter-based
stopping rule: stop when every correction is below ``tol`` times the parameter's
a-priori (conditional) σ = 1/√N_ii (the cost alone barely changes along the weak
bending modes of large blocks). From start values whose normal matrix is not positive
definite the result reports ``converged=False`` with a reason that points to
:func:`orientviz.approximate.approximate_values`.

Self-calibration (``additional=``): the parameters border the reduced system
(:mod:`orientviz.bundle.problem._ap_normal` assembles E, F;
:mod:`orientviz.bundle.problem._border` solves). From poor approximations (start σ0 ≥
``BundleOptions.poor_start_sigma0``) the first step holds the parameters at their values: they
model image errors of a few µm and should not absorb the errors of the approximations.
The result is finished by :func:`orientviz.bundle.loop._finish.finish_result`.

A robust loss (``BundleOptions.loss``: Huber, Cauchy, soft-L1 of each ray, as Ceres's)
is minimised inside the same loop (:mod:`orientviz.bundle.loop._loss`); the result then
refers to the rays' σ/√w with w = ρ′ at the solution (:func:`robust_end`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...adjust.loop import Damping, Evaluation, StopRule, iterate
from ...adjust.result import Iteration
from ...blas import blas_threads
from ...block import Block
from ...errors import InputError, NotDeterminableError
from .._block_cameras import camera_keywords, held_plain_camera
from .._options import BundleOptions
from .._result import BundleResult
from ..problem import BundleProblem, BundleState, point_setup
from ..problem._checks import check_connected, check_datum, check_determinable
from ._finish import RunEnd, finish_result
from ._loss import RobustLoss
from ._steps import BundleSteps

#: A robust loss (``BundleOptions.loss``) allows this many times ``max_iter`` steps: its
#: reweighted steps converge linearly, not quadratically as Gauss-Newton steps do.
ROBUST_ITER_FACTOR: int = 4
#: … and stops also when a step lowers Σ ρ by less than this fraction (Ceres's function
#: tolerance) unless ``BundleOptions.ftol`` is set: a point seen only by down-weighted rays
#: may drift away slowly for ever (its rays' cost falls towards a limit).
ROBUST_FTOL: float = 1e-6

#: Up to this many images the bundle's BLAS calls are small (reduced systems of a few
#: thousand rows at most, stacked products of tiny blocks): OpenBLAS's threads then only
#: wait for each other, and the adjustment runs BLAS on one thread (threadpoolctl).
ONE_BLAS_THREAD_MAX_IMAGES: int = 500

#: The first λ of the ``"trust"`` damping (the SfM imports; ``"fallback"`` starts undamped)
#: for least squares: the damping is scaled per image in its scene's frame
#: (:mod:`orientviz.bundle.problem._damping`), so a small λ already holds back the weak
#: motions of narrow-angle images; ten times less (1e-6) lets Ladybug's first steps run
#: into another basin.
TRUST_LAMBDA0: float = 1e-5
#: … and with a robust loss: its first steps are least-squares steps pulled by the gross
#: errors before the loss is switched on (``_steps``); damped ten times more they keep the
#: basins measured for the losses (at 1e-5 BAL 16-22106 ends 0.5 % higher, Huber and soft-L1).
TRUST_LAMBDA0_ROBUST: float = 1e-4


def bundle_adjust(
    block: Block,
    *,
    control: str = "fixed",
    additional=None,
    ap_group=None,
    ap_sigma=None,
    auxiliary: list | None = None,
    precision: bool = True,
    callback: Callable[[Iteration], object] | None = None,
    options: BundleOptions | None = None,
    max_iter: int | None = None,
    tol: float | None = None,
    solver: str | None = None,
    history_x: bool | None = None,
) -> BundleResult:
    """Adjust a block by the bundle method (see module docstring for the model).

    Parameters
    ----------
    block : Block
        Approximate values in ``images.X0``/``angles`` (rad, ``block.sequence``) and
        ``points.xyz`` (m); see :func:`orientviz.approximate.approximate_values`.
    control : {"fixed", "weighted"}
        ``"fixed"``: every given coordinate of a control point is held fixed.
        ``"weighted"``: given coordinates with ``points.sigma`` > 0 are observations
        with that σ (m), σ = 0 still fixes. Check points (role 2) are left out and
        intersected afterwards with the adjusted orientations.
    additional : AdditionalParameters, optional
        Self-calibration set (``design(xy) -> (n, 2, k)`` in mm per unit, evaluated at the
        observed coordinates): ``x_obs + v = project(...) + A(x_obs)·a``.
        A set's name (``"ebner12"``, ``"brown"``, ``"gruen44"``) stands for
        ``ap_set(name)``; a :class:`LensModel` estimates the camera's own parameters.
        None (default): the models the block's cameras state (``block.cameras.model``,
        e.g. a COLMAP import's free focal length; :func:`~orientviz.bundle.block_camera_options`),
        none if they state none; ``False``: none, whatever the cameras state. A lens
        model that estimates nothing and has no distortion at the cameras' c, x0, y0 is
        the plain model and is solved as such (``result.camera`` still reports it;
        :func:`~orientviz.bundle._block_cameras.held_plain_camera`).
    ap_group : array_like of int, shape (m,), optional
        Group of each image for the additional parameters (default: one group; with
        the block's camera models one per camera).
    ap_sigma : float or array_like (k,), optional
        σ of the pseudo-observations a = 0 (units of the parameters); None = free (or
        what the block's cameras state).
    precision : bool
        Compute per-image 6×6 and per-point 3×3 cofactor blocks, redundancy numbers and
        normalised residuals (:mod:`orientviz.bundle.precision`).
    callback : callable, optional
        Called with each new :class:`Iteration`.
    auxiliary : list of Auxiliary, optional
        GNSS / statoscope / APR data as joint observations with offset/drift unknowns
        per strip (:mod:`orientviz.bundle.problem._auxiliary`), also together with
        ``additional`` (both border the reduced system:
        :mod:`orientviz.bundle.problem._auxiliary_border`). Estimates in ``result.auxiliary``
        (:class:`~orientviz.block.AuxiliaryEstimates`: offsets, sigma (m), residuals),
        ``cofactor_groups["auxiliary"]``; the rows are appended to the observations
        (``obs_slices["auxiliary"]``, m) and with ``precision`` get redundancy numbers
        and normalised residuals; the cofactor blocks of orientations and points then
        include the uncertainty of the offsets/drifts. The datum check is left to the
        normal equations.

    options : BundleOptions, optional
        The solver's knobs (:class:`~orientviz.bundle.BundleOptions`: iterations,
        tolerance, the reduced system's solver, chord steps, the border's and the
        precision's limits); default ``BundleOptions()``.
    max_iter, tol, solver, history_x : optional
        Shorthands: each one given replaces that field of ``options``
        (``max_iter`` Gauss-Newton steps at most; ``tol`` the stopping rule's bound on
        every correction in units of its a-priori conditional σ = 1/√N_ii; ``solver``
        ``"auto"``, ``"banded"``, ``"dense"`` or ``"sparse"`` — the result's ``solver``
        is the one used, ``reduced_info["solver_reason"]`` says why — or ``"reference"``,
        the textbook iteration of :mod:`orientviz.bundle.reference` (small blocks; no
        auxiliary data); ``history_x`` keep the full parameter vector per iteration).

    Returns
    -------
    BundleResult
        Typed fields ``exterior`` ((m, 6): X0, Y0, Z0 m, ω, φ, κ rad), ``points`` ((p, 3)
        m; fixed control at its given value, check points intersected), ``additional``
        (q,), ``check_points`` (:class:`~orientviz.block.CheckPoints`, ``check_rms`` m
        X/Y/Z), ``auxiliary``, ``used_obs``, ``solver``, ``reduced_info``, and with the
        precision ``ray_gains``, ``exterior_pairs``, ``redundancy_xy``; parameter
        blocks ``"exterior"``, ``"points"``, ``"additional"`` of ``x``; residuals
        v = f − l: the 2n image coordinates (x, y per observation, mm) first, then the
        pseudo-observations (``obs_slices`` names the ranges).
    """
    opts = BundleOptions() if options is None else options
    given = dict(max_iter=max_iter, tol=tol, solver=solver, history_x=history_x)
    given = {k: v for k, v in given.items() if v is not None}
    if given:
        opts = opts.replace(**given)
    max_iter, tol, ftol = opts.max_iter, opts.tol, opts.ftol
    # the block's camera models unless the caller gave additional (.._block_cameras)
    additional, ap_group, ap_sigma = camera_keywords(block, additional, ap_group, ap_sigma)
    if opts.loss != "none":  # reweighted steps converge linearly (._loss)
        max_iter *= ROBUST_ITER_FACTOR
        ftol = ftol or ROBUST_FTOL
    setup = point_setup(block, control)
    check_connected(block, setup)
    check_determinable(block, setup)
    if not auxiliary:
        check_datum(block, setup)
    if opts.solver == "reference":  # the textbook iteration (bundle/reference.py), no fast path
        if auxiliary:
            raise InputError("solver='reference' takes no auxiliary data (GNSS, statoscope, APR)")
        if opts.loss != "none":
            raise InputError("solver='reference' is least squares only (no robust loss)")
        from ._reference_result import reference_result  # the textbook iteration: only when asked

        return reference_result(
            block, setup, control=control, additional=additional, ap_group=ap_group,
            ap_sigma=ap_sigma, precision=precision, callback=callback, options=opts,
        )  # fmt: skip
    # a held lens model without distortion is the plain model: solved as such, its camera
    # reported as the lens model's run would (.._block_cameras)
    held = held_plain_camera(block, additional, ap_group, setup.used_obs)
    if held is not None:
        additional = None
    one_thread = block.n_images <= ONE_BLAS_THREAD_MAX_IMAGES
    with blas_threads(1 if one_thread else None):  # many small products: one BLAS thread
        prob = BundleProblem(
            block, setup, additional=additional, ap_group=ap_group, ap_sigma=ap_sigma,
            auxiliary=auxiliary, options=opts,
        )  # fmt: skip
        red_names = prob.names(exterior_only=True)
        xyz0 = block.points.xyz.copy()
        fixed = setup.fixed
        xyz0[fixed] = np.where(np.isfinite(setup.known[fixed]), setup.known[fixed], xyz0[fixed])
        st = BundleState(
            block.images.X0.copy(), block.images.angles.copy(), xyz0, np.zeros(prob.q),
            np.zeros(prob.na),
        )  # fmt: skip
        keep_x = (
            (block.n_images <= opts.history_x_limit)
            if opts.history_x is None
            else bool(opts.history_x)
        )
        dof = prob.redundancy

        def s0(c):
            return float(np.sqrt(c / dof)) if dof > 0 else float("nan")

        loss = RobustLoss.named(opts.loss, opts.loss_scale)
        steps = BundleSteps(prob, red_names, keep_x, precision, loss)
        ev0 = steps.start(st)
        # additional parameters model image errors of a few µm: from approximations whose
        # misclosures are far larger (σ0 ≥ opts.poor_start_sigma0) the first step is taken with
        # the parameters held at their values — it costs no border, and the parameters do
        # not absorb errors of the approximations (the first joint step then starts close)
        hold_first = bool(prob.q) and s0(ev0.cost) >= opts.poor_start_sigma0
        del ev0  # the loop takes it over (and releases it after the first step)
        steps.hold_first = hold_first
        steps.stop_ftol = ftol or 0.0
        run = iterate(
            steps,
            st,
            redundancy=dof,
            damping=Damping(
                opts.damping,
                lambda0=TRUST_LAMBDA0 if loss is None else TRUST_LAMBDA0_ROBUST,
                poor_start_sigma0=opts.poor_start_sigma0,
                first=2 if hold_first else 1,
            ),  # fmt: skip
            stop=StopRule(
                tol=tol,
                ftol=ftol,
                may_stop=lambda it: (
                    not (prob.run.border.hold or steps.local_step) and steps.may_stop()
                ),
            ),  # fmt: skip
            max_iter=max_iter,
            # derivatives at the new state: for the next iteration, the precision or the
            # check of a damped start (not after the last step of a screening run, nor after
            # a step that meets the stopping rule or, robust, is expected to meet ftol: the
            # loop stops there once it is accepted)
            jacobian_after=lambda it, run: (
                (it < max_iter and not steps.stops(tol) and not steps.expects_stop(ftol))
                or precision
                or run.damped_start
                or prob.aux is not None
            ),
            callback=callback,
            on_accept=steps.accepted,
            on_iteration=steps.begin,
        )
        st, history, converged, reason = run.state, run.history, run.converged, run.reason
        # the derivatives and a camera model's design at the last iterate are read by the
        # precision, the check of a damped start and auxiliary data only
        need = precision or run.damped_start or prob.aux is not None
        if need and loss is None and getattr(run.evaluation.data, "deferred", False):
            steps.resolve(st, run.evaluation)  # the loop asked for derivatives (robust: below)
        if not precision:  # the Schur formation's maps and work arrays: not held after the loop
            prob.reduced.release_maps()
        steps.chord_factor = steps.chord_pending = None
        rw, Je, Jp = run.evaluation.data
        cost, obs_sigma = run.evaluation.cost, None
        if loss is not None:  # the result refers to the rays' σ/√ρ′ at the last iterate
            rw, Je, Jp, cost, obs_sigma = robust_end(
                prob, steps, st, jacobian=need, last=run.evaluation
            )
            steps.lin = None
        elif need and steps.is_local(run.evaluation):  # derivatives by ω, φ, κ are needed
            rw, Je, Jp = prob.residuals(st, jac=True)
        damped_start, lin = run.damped_start, steps.lin
        prob.run.border.hold = prob.run.border.reuse = False
        if need:
            prob.design_at(st)  # a lens model: its design at the final iterate
        if not converged:
            lin = None
        if precision and lin is not None:  # the precision reuses the last factor: not held
            prob.reduced.release_maps()  # (else it forms S at the solution with them)
        if damped_start:  # a start that needed damping: prove the solution is determinable
            try:
                prob.solve(prob.normal(st, rw, Je, Jp), red_names)
            except NotDeterminableError:
                converged, precision = False, False
                reason = (
                    f"no convergence from poor approximate values (start σ0 = {history[0].sigma0:.3g}): "
                    "the normal equations are not positive definite there; compute better "
                    "approximations, e.g. with orientviz.approximate.approximate_values"
                )
        end = RunEnd(st, rw, Je, Jp, cost, history, converged, reason, precision, lin, obs_sigma)
        res = finish_result(prob, end)
    if held is not None:
        res.camera = held.estimates(np.zeros(0), None, res.sigma0)
    return res


def robust_end(
    prob: BundleProblem,
    steps: BundleSteps,
    st: BundleState,
    jacobian: bool = True,
    last: Evaluation | None = None,
):
    """The last iterate of a robust run as a weighted least-squares solution: each ray's
    weight factor w = ρ′(s) there, its σ/√w, vᵀPv with those weights (the pseudo-
    observations' unchanged), and the weighted misclosures and Jacobians the precision
    reads (the problem's ray weights are set to 1/σ·√w; without ``jacobian`` Je = Jp =
    None: a result without precision reads only the misclosures).

    ``last``: the loop's evaluation at ``st``; where it holds a pinhole's robust
    linearisation (s, ρ′ and the Jacobians by ω, φ, κ) these are taken from it — the
    values the evaluation below forms.

    Returns
    -------
    (rw, Je, Jp, cost, obs_sigma)
        ``obs_sigma`` (n_obs, 2): σ of every observation of the block (mm), σ/√w for the
        adjusted rays.
    """
    weight = prob.obs.weight
    weight[...] = steps.base_weight
    data = None if last is None else last.data
    terms = getattr(data, "terms", None)
    if terms is not None and prob.ap.lens is None and not data.local and data[1] is not None:
        s, w = terms
        weight *= np.sqrt(w)[:, None]
        steps.reweigh_design()
        rw, Je, Jp = data if jacobian else (data[0], None, None)
    else:
        rw = prob.residuals(st, jac=False, keep=True)[0]
        s = np.einsum("ij,ij->i", rw, rw)
        w = steps.loss.weights(s)
        weight *= np.sqrt(w)[:, None]
        steps.reweigh_design()
        rw, Je, Jp = prob.residuals(st, jac=jacobian)
    cost = float(np.dot(w, s)) + prob.cost(st, rw[:0])
    obs_sigma = prob.block.observations.sigma.copy()
    obs_sigma[prob.obs.index] /= np.sqrt(w)[:, None]
    return rw, Je, Jp, cost, obs_sigma
