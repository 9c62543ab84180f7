"""Block adjustment with independent models (Ackermann 1974, Table 1, method 2).

Every model (a stereo pair, formed by :func:`~.model_formation.form_models`) is moved into
the object frame by a 3D similarity transformation ::

    X_t + v = λ_j · R_j · m_jt + T_j          (object coordinates in m, R_j orthogonal)

with the model coordinates m_jt taken as observations and the object coordinates X_t of
all points and projection centres as unknowns; control coordinates are fixed (or
weighted). Points shared by several models and the projection centres (each shared by
the two models of an image) tie the block together.

Two solvers are offered:

* ``method="rigorous"``: all 7 parameters of every model (rotation as a rotation-vector
  increment about the current R_j, scale λ_j, translation T_j) in one Gauss-Newton
  adjustment; the point coordinates are eliminated (their normal matrix is diagonal) and
  the sparse reduced system of the 7·n model parameters is solved
  (:mod:`orientviz.stereo_models._normal`).
* ``method="pat-m"``: the planimetry/height iteration of PAT-M (Ackermann, Ebner, Klein):
  a planimetric 4-parameter similarity per model (scale, rotation about the vertical,
  X and Y shift) with planimetric control, then a height adjustment with 3 parameters per
  model (Z shift and two tilts about the model centre) with height control, repeated
  (Table 2: 3 iterations). It converges to practically, not exactly, the rigorous result:
  the planimetric step ignores the heights of the residuals.

  The projection centres take part in the *height* step with all three coordinates: a
  tilt φ (ω) moves a centre sideways by its height above the model centre times φ (ω), and
  consecutive models must put their common centre at the same X, Y — this, not the
  heights, fixes the tilt between consecutive models, whose common points lie on one line
  across the strip right below the common centre. (Findings while building this: with
  the centres in the height step by their Z only, the heights of a 4 × 10 block came out
  12 × worse than the rigorous ones; with them also in the planimetric step the
  iteration crawled at a factor 0.7 per iteration.) The planimetric step uses the ground
  points only. Convergence is linear, corrections shrink ≈ 3 × per iteration.

Weights: model coordinates σ_xy (m) in planimetry and σ_z in height, the same for the
projection centres; by default σ_xy = σ_image · m_B and σ_z = √2 · (H/B) · σ_xy from the
image σ, the image scale and the base-to-height ratio, so that σ̂0 ≈ 1 for a block with
just random image errors. Residuals v = λRm + T − X are in m (object frame).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ..adjust import iterate
from ..block import Block, check_points_of
from ..errors import InputError, NotDeterminableError
from . import _joint as mj
from ._deformation import model_ap_set
from ._formation import ModelSet, form_models
from ._normal import scalar_cofactors, solve_rows
from ._result import ModelsResult
from ._setup import TieSetup, check_datum, tie_setup
from ._steps import PatmSteps, RigorousSteps, model_params, rows3, stop_rule

F64 = NDArray[np.float64]


def default_model_sigma(block: Block, ms: ModelSet) -> tuple[float, float]:
    """σ of model coordinates (planimetry, height) in m that :func:`independent_models`
    uses by default: σ_xy = σ_image · m_B, σ_z = √2 · (H/B) · σ_xy (medians of the image σ,
    the principal distance, the flying height above the points and the models' bases)."""
    s_img = float(np.median(block.observations.sigma))  # mm
    c = float(np.median(block.cameras.c))  # mm
    H = float(np.median(block.images.X0[:, 2]) - np.median(block.points.xyz[:, 2]))
    scale = H / (c / 1000.0)
    base = float(np.median(ms.centres[:, 1, 0]))
    s_xy = s_img / 1000.0 * scale
    return s_xy, math.sqrt(2.0) * H / base * s_xy


def independent_models(
    block: Block,
    *,
    method: str = "rigorous",
    models: ModelSet | None = None,
    control: str = "fixed",
    sigma_model: tuple[float, float] | None = None,
    use_centres: bool = True,
    max_iter: int | None = None,
    tol: float | None = None,
    precision: bool = False,
    deformation: str | list[str] | None = None,
    deformation_group: str = "model",
    deformation_sigma: float | None = 1000.0,
    auxiliary: list | None = None,
) -> ModelsResult:
    """Adjust a block by independent models.

    Parameters
    ----------
    block : Block
        Image observations and approximate orientations; control points with given
        coordinates. ``images.strip`` must be set (models = consecutive images).
    method : {"rigorous", "pat-m"}
        7-parameter adjustment, or the planimetry/height iteration (see module docstring).
    models : ModelSet, optional
        Models already formed (default: :func:`form_models` on ``block``).
    control : {"fixed", "weighted"}
        Given control coordinates held fixed, or weighted with their ``points.sigma``.
    sigma_model : tuple of float, optional
        σ of model coordinates (planimetry, height) in m (default from the image σ).
    use_centres : bool
        Tie consecutive models by their common projection centre (PAT-M: in height only,
        see the module docstring).
    max_iter : int, optional
        Maximum Gauss-Newton steps (rigorous, default 15) or planimetry/height iterations
        (PAT-M, default 40).
    tol : float, optional
        Stop when all corrections are below ``tol · σ_xy`` (default 1e-4 for the
        quadratically converging rigorous solution, 1e-2 for PAT-M).
    precision : bool
        Compute the 3 × 3 cofactor blocks of all tie points (``cofactor_groups["points"]``).
    deformation : str or list of str, optional
        Model deformation parameters (self-calibration; rigorous method only): a set
        name or terms of :mod:`orientviz.stereo_models._deformation`.
    deformation_group : {"model", "strip", "block"} or array_like of int
        Parameters per model, shared per strip, or one set for the block.
    deformation_sigma : float or array_like, optional
        σ in mm of the pseudo-observations p = 0 (default 1000 mm: weak); None = free.
    auxiliary : list of Auxiliary, optional
        GNSS / statoscope (projection centres) and APR (tie point heights) data as joint
        observations with offsets/drifts per strip (:mod:`orientviz.bundle.problem._auxiliary`;
        rigorous method, ``use_centres=True`` for gnss/statoscope). With auxiliary data
        the control check is left to the normal equations (GNSS may give the datum).

    Returns
    -------
    ModelsResult
        ``x``: 7 parameters per model (X0, Y0, Z0 in m; ω, φ, κ in rad of R_j, sequence
        ω-φ-κ; λ) then X, Y, Z of every tie point (block points in ``point_index``,
        then the projection centres of the images in ``centre_image``). Typed fields:
        ``points`` (p, 3) adjusted coordinates of all block points (check points by
        transforming their model coordinates; NaN if in no model), ``check_points``,
        ``centres`` (m, 3) projection centres, ``sigma0_m`` (σ̂0 in m),
        ``sigma0_planimetry``/``sigma0_height`` (separate σ̂0 as in PAT-M, unit weight;
        × ``sigma_model`` gives m), ``rms_xy_m``, ``rms_z_m``, ``models`` (the ModelSet),
        ``method``. With deformation parameters: block ``"additional"`` (mm,
        group-major) and ``deformation`` (:class:`DeformationEstimates`: values (groups,
        k), sigma, analysis — :class:`~orientviz.bundle.APAnalysis`: t-tests, correlated
        pairs, correlations with the similarity parameters). With auxiliary data: block
        ``"auxiliary"`` and ``auxiliary`` (:class:`~orientviz.block.AuxiliaryEstimates`:
        offsets, sigma {kind: (strips, dims, 1 or 2)} m, residuals m).

    Raises
    ------
    InputError
        For an unknown method or control mode.
    NotDeterminableError, DatumDefectError
        For models that cannot be formed, disconnected blocks or missing control (the
        message names the models or parts).
    """
    if method not in ("rigorous", "pat-m"):
        raise InputError(f"method: expected 'rigorous' or 'pat-m', got {method!r}")
    ms = models if models is not None else form_models(block)
    tol = (1e-4 if method == "rigorous" else 1e-2) if tol is None else float(tol)
    max_iter = (15 if method == "rigorous" else 40) if max_iter is None else int(max_iter)
    su = tie_setup(block, ms, control=control, use_centres=use_centres)
    joint = deformation is not None or bool(auxiliary)
    if joint and method != "rigorous":
        raise InputError("deformation parameters and auxiliary data need method='rigorous'")
    if not auxiliary:
        check_datum(su, ms, need_xy=True, need_z=True)
    s_xy, s_z = sigma_model if sigma_model is not None else default_model_sigma(block, ms)
    n = ms.n_models
    lam = np.ones(n)
    R = ms.start_rotation.copy()
    T = ms.start_translation.copy()
    su.init_points(lam, R, T)
    w_c = np.array([1 / s_xy**2, 1 / s_xy**2, 1 / s_z**2])
    if joint:
        return _joint(
            block, ms, su, lam, R, T, w_c, s_xy, tol, max_iter, precision,
            deformation, deformation_group, deformation_sigma, auxiliary,
        )  # fmt: skip
    if method == "rigorous":
        converged, reason, sol, history = _run(
            RigorousSteps(su, w_c, s_xy), su, (lam, R, T), tol, s_xy, max_iter,
            f"corrections below {tol:g} σ_xy after {{it}} iterations",
            f"reached the maximum of {max_iter} iterations",
        )  # fmt: skip
    else:
        converged, reason, sol, history = _run(
            PatmSteps(su, w_c, s_xy), su, (lam, R, T), tol, s_xy, max_iter,
            "planimetry/height iteration converged after {iterations}",
            f"reached the maximum of {max_iter} planimetry/height iterations",
        )  # fmt: skip
    return _result(
        block, ms, su, lam, R, T, w_c, method, converged, reason, sol, history, precision
    )


def _joint(
    block, ms, su, lam, R, T, w_c, s_xy, tol, max_iter, precision,
    deformation, group, sigma, auxiliary,
):  # fmt: skip

    spec = model_ap_set(deformation) if deformation is not None else None
    js = mj.joint_setup(block, ms, su, w_c, spec, group, sigma, auxiliary)
    names = su.param_names(7) + js.names(ms)
    try:
        converged, reason, sol, p, g, history = mj.rigorous_joint(
            su, js, lam, R, T, w_c, s_xy, tol, max_iter, names
        )
    except NotDeterminableError as exc:
        if spec is None or sigma is not None and np.all(np.isfinite(sigma)):
            raise
        raise mj.explain_singular(
            exc,
            lambda: independent_models(
                block,
                models=ms,
                control=su_control(su),
                deformation=spec,
                deformation_group=group,
                deformation_sigma=1000.0,
                auxiliary=auxiliary,
                use_centres=su.centre_images.size > 0,
            ),
        ) from None
    # the base result with the deformed model coordinates of the rows
    m0 = su.m
    su.m = mj.deformed(su, js, p)
    try:
        res = _result(
            block, ms, su, lam, R, T, w_c, "rigorous", converged, reason, None, history, False
        )
    finally:
        su.m = m0
    res = mj.finish_joint(res, block, ms, su, js, lam, R, T, p, g, sol, names, w_c)
    if precision:
        res.cofactor_groups["points"] = mj.point_cofactors(sol, su)
    return res


def su_control(su: TieSetup) -> str:
    """The control mode a TieSetup was built with (weighted if any prior weight)."""
    return "weighted" if np.any(su.prior_w > 0) else "fixed"


def _run(
    problem, su: TieSetup, state, tol: float, s_xy: float, max_iter: int, done: str, most: str
):
    """Iterate ``problem`` on the engine's loop; (converged, reason, last solution, history)."""
    run = iterate(
        problem, state, redundancy=su.redundancy, max_iter=max_iter,
        stop=stop_rule(tol * s_xy, done),
    )  # fmt: skip
    reason = most if run.reason.startswith("reached the maximum") else run.reason
    return run.converged, reason, problem.last, run.history


def _separate_sigma0(su: TieSetup, r: F64, w_c: F64) -> tuple[float, float]:
    """σ̂0 of planimetry and of height as PAT-M reports them (separate redundancies).

    Planimetry: the X, Y residuals of the ground points, redundancy 2·k − 4·n − free X, Y;
    height: the Z residuals of all rows and the X, Y residuals of the projection centres,
    redundancy k + 2·k_c − 3·n − free Z − free X, Y of the centres. Unit weight.
    """
    pc = su.row_point >= su.tie_points.size
    g = ~pc
    n = su.n_models
    free = su.scalar >= 0
    n_tie = su.tie_points.size
    rl = 2 * int(g.sum()) - 4 * n - int(free[:n_tie, :2].sum())
    rh = (
        r.shape[0] + 2 * int(pc.sum()) - 3 * n - int(free[:, 2].sum()) - int(free[n_tie:, :2].sum())
    )
    vl = float(np.sum(r[g, :2] ** 2 * w_c[:2]))
    vh = float(np.sum(r[:, 2] ** 2 * w_c[2]) + np.sum(r[pc, :2] ** 2 * w_c[:2]))
    nan = float("nan")
    return (math.sqrt(vl / rl) if rl > 0 else nan), (math.sqrt(vh / rh) if rh > 0 else nan)


def _result(block, ms, su, lam, R, T, w_c, method, converged, reason, sol, history, precision):
    r, _ = rows3(su, lam, R, T)
    cost = float(np.sum(r**2 * w_c) + np.sum(su.prior_w * su.prior_e() ** 2))
    dof = su.redundancy
    s0 = math.sqrt(cost / dof) if dof > 0 else float("nan")
    x = np.concatenate([model_params(lam, R, T).ravel(), su.X.ravel()])
    n7 = 7 * ms.n_models
    names = [
        f"{mid}.{e}" for mid in ms.ids for e in ("X0", "Y0", "Z0", "omega", "phi", "kappa", "scale")
    ] + [f"{pid}.{c}" for pid in su.point_names for c in "XYZ"]
    xyz, centres = su.block_coordinates(block, ms, lam, R, T)
    s0_l, s0_h = _separate_sigma0(su, r, w_c)
    res = ModelsResult(
        x=x, names=names, sigma0=s0, redundancy=dof, residuals=r.ravel(),
        sigma_obs=np.tile(1.0 / np.sqrt(w_c), r.shape[0]), converged=converged, reason=reason,
        history=history, groups={"models": slice(0, n7), "points": slice(n7, x.size)},
        points=xyz, check_points=check_points_of(block, xyz),
        sigma0_planimetry=s0_l, sigma0_height=s0_h,
        method=method, models=ms, centres=centres, point_index=su.tie_points,
        centre_image=su.centre_images, sigma0_m=s0 * math.sqrt(1.0 / w_c[0]),
        rms_xy_m=float(np.sqrt(np.mean(r[:, :2] ** 2))), rms_z_m=float(np.sqrt(np.mean(r[:, 2] ** 2))),
        sigma_model=(1 / math.sqrt(w_c[0]), 1 / math.sqrt(w_c[2])),
        adjusted=(r.size + int(np.sum(su.prior_w > 0)), 7 * ms.n_models + su.n_scalar),
    )  # fmt: skip
    if precision and method == "rigorous" and sol is not None:
        res.cofactor_groups["points"] = scalar_cofactors(sol, su.scalar)
    elif precision:
        # one more rigorous linearisation at the PAT-M solution gives its precision
        r3, J = rows3(su, lam, R, T)
        k = r3.shape[0]
        sol = solve_rows(
            np.repeat(su.row_model, 3), J.reshape(3 * k, 7),
            su.scalar[su.row_point].ravel(), np.tile(w_c, k), r3.ravel(), su.n_models,
            su.n_scalar, prior_w=su.prior_w, prior_e=su.prior_e(), names=su.param_names(7),
        )  # fmt: skip
        res.cofactor_groups["points"] = scalar_cofactors(sol, su.scalar)
    return res
