"""Finishing a bundle adjustment: its :class:`~orientviz.bundle.BundleResult`.

Residual order (v = f − l): the image coordinates of *all* observations of the block
(x, y per observation, mm; rays to check points included but not adjusted — their
redundancy numbers are NaN), then the pseudo-observations of weighted control
coordinates (m), observed projection centres (m), attitudes (rad) and additional
parameters; ``obs_slices`` names these ranges. Check points are intersected with the
adjusted orientations from their own rays; the precision is
:func:`orientviz.bundle.precision.bundle_precision`'s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from ...block import CHECK, check_points_of
from ...errors import NotDeterminableError
from ...rotation import matrix_from_opk
from .._result import BundleResult
from ..model import normalised_block, project_block
from ..precision import bundle_precision
from ..precision._far import rays_about_their_mean, row_norms
from ..problem import BundleProblem, BundleState, wrap
from ..reduced import raise_not_determinable

F64 = NDArray[np.float64]


def _intersect_check_points(
    block, X0: F64, angles: F64, chk: NDArray[np.int64], prob=None, ap: F64 | None = None
) -> F64:
    """Check points intersected from their own rays with the adjusted orientations (m).

    Least-squares forward intersection (:func:`orientviz.orientation.intersection.intersect_points`),
    NaN for points with fewer than two rays or parallel rays. With a camera model
    (``prob.ap.lens``) the rays are first corrected by the estimated camera.
    """
    obs = block.observations
    col = -np.ones(block.n_points, np.int64)
    col[chk] = np.arange(chk.size)
    sel = np.flatnonzero(col[obs.point] >= 0)
    out = np.full((chk.size, 3), np.nan)
    if sel.size == 0:
        return out
    cam = block.images.camera
    xy, io = obs.xy[sel], (block.cameras.c[cam], block.cameras.x0[cam], block.cameras.y0[cam])
    image = obs.image[sel]
    if prob is not None and prob.ap.lens is not None:  # per ray: as a pinhole saw it
        xy, io_ray = prob.ap.lens.pinhole(ap, prob.ap.group[image], xy)
        image = np.arange(sel.size)  # one "image" per ray carries its ray's c, x0, y0
        X0, angles = X0[obs.image[sel]], angles[obs.image[sel]]
        io = (io_ray[:, 0], io_ray[:, 1], io_ray[:, 2])
    from ...orientation.intersection import intersect_points  # only a block with check points

    res = intersect_points(
        xy, image, col[obs.point[sel]], X0,
        matrix_from_opk(angles[:, 0], angles[:, 1], angles[:, 2], block.sequence),
        *io, sigma=obs.sigma[sel], n_points=chk.size, on_degenerate="nan",
    )  # fmt: skip
    return res.xyz


#: A point whose rays meet at less than this angle (rad) lies near infinity: its depth
#: along the rays is not determined (:func:`ray_parallax`).
FAR_PARALLAX: float = 1e-5

#: A point closer to a projection centre that sees it than this share of the block's
#: median ray length lies at that centre: the direction of its ray, and so the image
#: coordinates' derivatives (∝ 1/distance), are not determined (:func:`points_at_centres`).
AT_CENTRE: float = 1e-6


def points_at_centres(
    block, X0: F64, xyz: F64, points: NDArray[np.int64]
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """The rays of ``points`` (indices of the block's points) whose point lies at the
    projection centre of their image: length below :data:`AT_CENTRE` of the median ray.

    Parameters
    ----------
    block : Block
        The block (its observations' point and image indices).
    X0 : ndarray, shape (m, 3)
        Projection centres, in the block's length unit.
    xyz : ndarray, shape (p, 3)
        Object points, in the same unit.
    points : ndarray of int
        The points to look at (the point unknowns).

    Returns
    -------
    point, image : ndarray of int
        Point and image index of each such ray.
    """
    obs = block.observations
    length = np.linalg.norm(xyz[obs.point] - X0[obs.image], axis=1)
    mine = np.zeros(block.n_points, bool)
    mine[points] = True
    short = mine[obs.point] & (length < AT_CENTRE * np.nanmedian(length))
    return obs.point[short], obs.image[short]


def ray_parallax(block, X0: F64, xyz: F64) -> F64:
    """The largest angle (rad) between a point's rays and their mean direction, per
    point of ``block`` (NaN with fewer than two rays): projection centres ``X0`` (m,
    (m, 3)), points ``xyz`` (m, (p, 3)). Below :data:`FAR_PARALLAX` the point lies near
    infinity."""
    obs = block.observations
    d = xyz[obs.point] - X0[obs.image]
    with np.errstate(invalid="ignore", divide="ignore"):
        d /= row_norms(d)[:, None]
        _, m, cross = rays_about_their_mean(obs.point, d, block.n_points)
        cos = np.clip(np.einsum("ij,ij->i", d, m), -1.0, 1.0)
        ang = np.arctan2(row_norms(cross), cos)  # by its sine: exact for tiny angles
    out = np.full(block.n_points, -np.inf)
    np.maximum.at(out, obs.point, np.nan_to_num(ang, nan=np.inf))
    out[np.bincount(obs.point, minlength=block.n_points) < 2] = np.nan
    return out


@dataclass(frozen=True)
class RunEnd:
    """What the iterations of a bundle adjustment leave for its result.

    Attributes
    ----------
    state : BundleState
        The last accepted iterate.
    rw : ndarray, shape (n, 2)
        Weighted misclosures P½(l − f) of the adjusted rays at ``state``.
    Je, Jp : ndarray, shapes (n, 2, 6), (n, 2, 3)
        Their Jacobians by the exterior orientation (ω, φ, κ) and the points.
    cost : float
        vᵀPv at ``state``.
    history : list of Iteration
        One record per iteration.
    converged : bool
    reason : str
        Why the iterations stopped.
    precision : bool
        Whether the result gets cofactors, redundancy numbers, normalised residuals.
    lin : tuple or None
        ``(ne, fac, Je, Jp)`` of the last Gauss-Newton step when the precision may reuse
        its factor (:func:`orientviz.bundle.precision.bundle_precision`).
    obs_sigma : ndarray, shape (n_obs, 2), optional
        σ of the block's image observations as adjusted (mm; a robust loss: σ/√ρ′);
        None: ``block.observations.sigma``.
    """

    state: BundleState
    rw: F64
    Je: F64
    Jp: F64
    cost: float
    history: list
    converged: bool
    reason: str
    precision: bool
    lin: tuple | None = None
    obs_sigma: F64 | None = None


def finish_result(prob: BundleProblem, end: RunEnd) -> BundleResult:
    """The :class:`~orientviz.bundle.BundleResult` of ``prob`` at the end of a run.

    Residuals of every observation of the block (check-point rays included), the
    pseudo-observations, check points intersected with the adjusted orientations, the
    precision when asked (``end.precision``), the auxiliary data's estimates and a
    lens model's camera.
    """
    block, st, rw, Je, Jp = prob.block, end.state, end.rw, end.Je, end.Jp
    history, converged, reason, precision = end.history, end.converged, end.reason, end.precision
    names, dof, lin = prob.names(), prob.redundancy, end.lin
    sigma0 = float(np.sqrt(end.cost / dof)) if dof > 0 else float("nan")
    m, p, n = block.n_images, block.n_points, block.n_observations
    setup = prob.setup
    xyz = st.xyz.copy()
    # check points: intersect with the adjusted orientations from their own rays
    chk = np.flatnonzero(block.points.role == CHECK)
    if chk.size:
        xyz[chk] = _intersect_check_points(block, st.X0, st.angles, chk, prob, st.ap)
    check = check_points_of(block, xyz)
    # residuals of all image observations (v = f − l)
    obs = block.observations
    fa = _project_all(block, st, xyz, prob)
    v_img = (fa - obs.xy).reshape(-1)
    s_img = (obs.sigma if end.obs_sigma is None else end.obs_sigma).reshape(-1)
    parts_v, parts_s, slices = [v_img], [s_img], {"image": slice(0, 2 * n)}
    pos = 2 * n

    def add(name, v, s):
        nonlocal pos
        parts_v.append(v)
        parts_s.append(s)
        slices[name] = slice(pos, pos + v.size)
        pos += v.size

    w = prob.points.prior_w > 0
    add(
        "control",
        (st.xyz[prob.points.unknown] - prob.points.prior_obs)[w],
        1 / np.sqrt(prob.points.prior_w[w]),
    )
    w = prob.exterior.X0_w > 0
    add("X0_obs", (st.X0 - prob.exterior.X0_obs)[w], 1 / np.sqrt(prob.exterior.X0_w[w]))
    w = prob.exterior.angles_w > 0
    add(
        "angles_obs",
        wrap(st.angles - prob.exterior.angles_obs)[w],
        1 / np.sqrt(prob.exterior.angles_w[w]),
    )
    if prob.q:
        w = prob.ap.w > 0
        add("additional", st.ap[w], 1 / np.sqrt(prob.ap.w[w]))
    blocks = {"exterior": slice(0, 6 * m), "points": slice(6 * m, 6 * m + 3 * p)}
    if prob.q:
        blocks["additional"] = slice(6 * m + 3 * p, 6 * m + 3 * p + prob.q)
    x = np.concatenate([np.hstack([st.X0, st.angles]).ravel(), xyz.ravel(), st.ap])
    res = BundleResult(
        x=x,
        names=names,
        sigma0=sigma0,
        redundancy=int(dof),
        residuals=np.concatenate(parts_v),
        sigma_obs=np.concatenate(parts_s),
        converged=converged,
        reason=reason,
        history=history,
        groups=blocks,
        obs_slices=slices,
        exterior=np.hstack([st.X0, st.angles]),
        points=xyz,
        check_points=check,
        additional=st.ap.copy(),
        used_obs=setup.used_obs,
        adjusted=(int(prob.n_eq), int(prob.n_unknowns)),
        solver=prob.reduced.solver,
        reduced_info=dict(prob.reduced.info, **_border_info(prob)),
    )
    if precision:
        try:
            bundle_precision(res, prob, st, rw, Je, Jp, lin)
        except (np.linalg.LinAlgError, scipy.linalg.LinAlgError, ValueError) as exc:
            # only reachable from a state the iterations did not settle (diverged start
            # values leave singular or non-finite point blocks): keep the result, say why
            # it carries no precision instead of letting a numerical error escape
            far = _far_points(prob, st)
            at, at_image = points_at_centres(block, st.X0, st.xyz, prob.points.unknown)
            converged_note = "" if converged else " (not converged)"
            if at.size:  # a point that converged onto a camera: its ray has no direction
                ids = ", ".join(
                    f"{block.points.ids[j]} at {block.images.ids[i]}"
                    for j, i in zip(at[:5], at_image[:5], strict=True)
                )
                res.precision_error = (
                    f"no precision at the last{converged_note} state: {at.size} ray(s) end at "
                    f"their own projection centre ({ids}{' …' if at.size > 5 else ''}): the "
                    "point lies on the camera, its ray's direction is not determined"
                )
            elif far.size:  # points that went to infinity (a robust loss lets them): kept
                ids = ", ".join(str(block.points.ids[j]) for j in far[:5])
                res.precision_error = (
                    f"no precision at the last{converged_note} state: {far.size} point(s) "
                    f"near infinity (rays meet at < {FAR_PARALLAX:g} rad: {ids}"
                    f"{' …' if far.size > 5 else ''}), their depth is not determined"
                )
            elif converged:
                # a converged state with a singular reduced system: the count checks
                # before the iterations (bundle_checks) missed a geometric defect; name
                # the parameters instead of ending in a numerical error
                blocks = prob.normal(st, rw, Je, Jp).blocks
                try:
                    raise_not_determinable(prob.reduced, blocks, names[: 6 * prob.m], str(exc))
                except NotDeterminableError as err:
                    raise err from exc
            else:
                res.precision_error = (
                    f"no precision at the last (not converged) state: {type(exc).__name__}: {exc}"
                )
    if prob.aux:
        from ..problem._auxiliary import finish_bundle  # only a block with auxiliary data

        finish_bundle(res, prob, st, rw, Je, Jp)
    if prob.ap.lens is not None:
        Q = res.cofactor_groups.get("additional") if prob.q else None
        res.camera = prob.ap.lens.estimates(st.ap, Q, res.sigma0)
    return res


def _far_points(prob: BundleProblem, st: BundleState) -> NDArray[np.int64]:
    """Indices of the adjusted points near infinity at ``st`` (:func:`ray_parallax`)."""
    par = ray_parallax(prob.block, st.X0, st.xyz)
    far = np.zeros(prob.block.n_points, bool)
    far[prob.points.unknown] = par[prob.points.unknown] < FAR_PARALLAX
    return np.flatnonzero(far)


def _project_all(block, st, xyz, prob) -> F64:
    """Image coordinates (n, 2) mm of all of the block's rays at ``st`` (``xyz``: its
    points with the check points intersected)."""
    cam = block.images.camera
    obs = block.observations
    if prob.ap.lens is not None:  # the camera model predicts every ray
        seq = block.sequence
        nrm = normalised_block(st.X0, st.angles, obs.image, xyz[obs.point], seq, False)[0]
        return prob.ap.lens.evaluate(st.ap, prob.ap.group[obs.image], nrm, obs.xy, False)[0]
    io = (block.cameras.c[cam], block.cameras.x0[cam], block.cameras.y0[cam])
    rays = slice(None)
    f = np.empty((obs.image.size, 2))
    if prob.run.projected is not None and prob.run.projected[0] is st:
        # the adjusted rays were projected at st by the last evaluation (the same
        # kernel on the same values: the same numbers); the others are projected here
        f[prob.obs.index] = prob.run.projected[1]
        rest = np.ones(obs.image.size, bool)
        rest[prob.obs.index] = False
        rays = np.flatnonzero(rest)
    f[rays] = project_block(
        st.X0, st.angles, *io, obs.image[rays], xyz[obs.point[rays]], block.sequence
    )
    if prob.q:
        f[prob.obs.index] += np.einsum(
            "nij,nj->ni",
            prob.ap.A,
            st.ap.reshape(prob.ap.G, prob.ap.k)[prob.ap.group[prob.obs.image]],
        )
    return f


def _border_info(prob) -> dict:
    """How the additional-parameter border was solved in each solve (formed / cg steps)."""
    return {"ap_border": list(prob.run.border.log)} if prob.q else {}
