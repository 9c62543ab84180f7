"""Checks before a bundle adjustment: roles of points, determinability, datum.

Ackermann (1974, §12) lists the "checks of the data for formal errors and for the
minimum conditions of solvability" as part of every aerotriangulation program. These
functions name what is wrong instead of letting a solver fail on a singular matrix.
Units: m for object coordinates and their σ.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.csgraph import connected_components

from ...block import CHECK, CONTROL, Block
from ...errors import DatumDefectError, InputError, NotDeterminableError
from ...plausibility import is_aerial
from ..reduced._structure import stable_order

F64 = NDArray[np.float64]

#: σ (m) used for a *fixed* coordinate of a point that is not fixed in all three
#: coordinates (e.g. a height control point): a very strong pseudo-observation.
FIXED_SIGMA_M: float = 1e-6


@dataclass
class PointSetup:
    """How each point enters the adjustment.

    Attributes
    ----------
    fixed : ndarray of bool, shape (p,)
        Point held fixed in all three coordinates (not an unknown).
    unknown : ndarray of bool, shape (p,)
        Point is an unknown of the adjustment.
    prior_sigma : ndarray, shape (p, 3)
        σ (m) of coordinate pseudo-observations of unknown points; inf = none.
    known : ndarray, shape (p, 3)
        The given coordinates (NaN where not given).
    used_obs : ndarray of bool, shape (n,)
        Observations that enter the adjustment (check points' rays do not).
    """

    fixed: NDArray[np.bool_]
    unknown: NDArray[np.bool_]
    prior_sigma: F64
    known: F64
    used_obs: NDArray[np.bool_]


def point_setup(block: Block, control: str) -> PointSetup:
    """Decide per point and coordinate: fixed, weighted or free (see :func:`bundle_adjust`)."""
    if control not in ("fixed", "weighted"):
        raise InputError(f"expected control='fixed' or 'weighted', got {control!r}")
    pts = block.points
    p = len(pts)
    is_ctrl = pts.role == CONTROL
    known = np.where(is_ctrl[:, None], pts.xyz_known, np.nan)
    given = np.isfinite(known)
    sig = np.asarray(pts.sigma, dtype=float)
    if control == "fixed":
        coord_fixed = given
        weighted = np.zeros_like(given)
    else:
        coord_fixed = given & (sig == 0)
        weighted = given & np.isfinite(sig) & (sig > 0)
    rays = np.bincount(
        block.observations.point[pts.role[block.observations.point] != CHECK], minlength=p
    )
    fixed = coord_fixed.all(axis=1) | ((rays == 0) & is_ctrl)
    prior = np.full((p, 3), np.inf)
    prior[weighted] = sig[weighted]
    prior[coord_fixed & ~fixed[:, None]] = FIXED_SIGMA_M
    unknown = ~fixed & (pts.role != CHECK)
    used = pts.role[block.observations.point] != CHECK
    prior[~unknown] = np.inf
    return PointSetup(fixed, unknown, prior, known, used)


def check_determinable(block: Block, setup: PointSetup) -> None:
    """Raise for tie points with fewer than two rays and images with fewer than 3 points."""
    obs = block.observations
    p = block.n_points
    rays = np.bincount(obs.point[setup.used_obs], minlength=p)
    has_prior = np.isfinite(setup.prior_sigma).all(axis=1)
    weak = np.flatnonzero(setup.unknown & (rays < 2) & ~has_prior)
    if weak.size:
        ids = [block.points.ids[i] for i in weak[:8]]
        more = f" and {weak.size - 8} more" if weak.size > 8 else ""
        raise NotDeterminableError(
            f"{weak.size} point(s) are seen in fewer than two images and cannot be intersected: "
            f"{', '.join(ids)}{more}; remove them or measure them in another image",
            parameters=[f"{i}.X" for i in ids],
            defect=3 * int(weak.size),
        )
    per_image = np.bincount(obs.image[setup.used_obs], minlength=block.n_images)
    observed_eo = np.isfinite(block.images.X0_obs).all(axis=1) & np.isfinite(
        block.images.angles_obs
    ).all(axis=1)
    few = np.flatnonzero((per_image < 3) & ~observed_eo)
    if few.size:
        ids = [block.images.ids[i] for i in few[:8]]
        raise NotDeterminableError(
            f"{few.size} image(s) observe fewer than 3 points, their orientation is not "
            f"determinable: {', '.join(ids)}",
            parameters=[f"{i}.X0" for i in ids],
            defect=6 * int(few.size),
        )


def check_connected(block: Block, setup: PointSetup) -> None:
    """Raise if the images fall apart into groups that share no point."""
    obs = block.observations
    m, p = block.n_images, block.n_points
    u = setup.used_obs
    # the graph of images and points: one row per image listing its points (m + point),
    # formed as CSR directly (no sort of a COO matrix's entries)
    img, pt = obs.image[u], obs.point[u]
    order = stable_order(img, m)
    indptr = np.zeros(m + p + 1, np.int64)
    np.cumsum(np.bincount(img, minlength=m), out=indptr[1 : m + 1])
    indptr[m + 1 :] = indptr[m]
    g = sp.csr_matrix((np.ones(img.size), m + pt[order], indptr), shape=(m + p, m + p))
    ncomp, labels = connected_components(g, directed=False)
    img_labels = labels[:m]
    comps = np.unique(img_labels)
    if comps.size <= 1:
        return
    sizes = np.array([(img_labels == c).sum() for c in comps])
    main = comps[np.argmax(sizes)]
    stray = np.flatnonzero(img_labels != main)
    ids = [block.images.ids[i] for i in stray[:8]]
    more = f" and {stray.size - 8} more" if stray.size > 8 else ""
    raise NotDeterminableError(
        f"the block is disconnected: {comps.size} groups of images share no point; images "
        f"{', '.join(ids)}{more} are not tied to the largest group — add tie points or adjust "
        "the groups separately",
        parameters=[f"{i}.X0" for i in ids],
        defect=7 * (comps.size - 1),
    )


def datum_defect(block: Block, setup: PointSetup) -> tuple[int, str]:
    """Number of free datum parameters (0…7) and what is missing.

    Counts control information: planimetric (X, Y) and height (Z) points that are
    given (fixed or weighted), plus observed projection centres (each coordinate on its
    own: a Z-only observation is a height). A 3D similarity datum needs ≥ 2 planimetric
    points (shift X, Y, rotation κ, scale) and ≥ 3 non-collinear heights (shift Z, tilts
    ω, φ). A height without given X, Y is placed at its approximate position (points:
    ``points.xyz``, centres: ``images.X0``); heights without any finite position cannot
    help against the tilts and are not counted for them. This is a necessary-condition
    count, not a proof of regularity; the solver still diagnoses a singular system.
    """
    free, missing = _datum_elements(block, setup)
    return len(free), "; ".join(missing)


def _finite_rows(a: F64) -> F64:
    return a[np.isfinite(a).all(axis=1)]


def _datum_elements(block: Block, setup: PointSetup) -> tuple[list[str], list[str]]:
    """(free datum elements by name, what would fix them) — see :func:`datum_defect`."""
    known = setup.known
    ctrl_plan = np.isfinite(known[:, 0]) & np.isfinite(known[:, 1])
    ctrl_h = np.isfinite(known[:, 2])
    xy = [known[ctrl_plan, :2]]
    # height points without given X, Y: their approximate position decides collinearity
    hpos = np.where(np.isfinite(known[:, :2]), known[:, :2], block.points.xyz[:, :2])
    hxy = [hpos[ctrl_h]]
    img = block.images
    s = img.X0_sigma
    ok = np.isfinite(img.X0_obs) & np.isfinite(s) & (s >= 0)
    xy.append(img.X0_obs[ok[:, 0] & ok[:, 1], :2])
    cpos = np.where(ok[:, :2], img.X0_obs[:, :2], img.X0[:, :2])
    n_h = int(ctrl_h.sum() + ok[:, 2].sum())  # every height, positioned or not
    hxy.append(cpos[ok[:, 2]])
    # an image with observed position *and* attitude fixes translation and rotation;
    # any further observed coordinate or a second planimetric point fixes the scale
    a_ok = np.isfinite(img.angles_obs) & np.isfinite(img.angles_sigma) & (img.angles_sigma >= 0)
    anchor = ok.all(axis=1) & a_ok.all(axis=1)
    if anchor.any():
        others = ok.any(axis=1) & (np.arange(len(anchor)) != np.flatnonzero(anchor)[0])
        if others.any() or ctrl_plan.sum() + ctrl_h.sum() >= 1:
            return [], []
        return ["scale"], ["a second observed position or a control point (scale)"]
    plan = np.unique(np.round(_finite_rows(np.concatenate(xy)), 3), axis=0)
    heights = np.unique(np.round(_finite_rows(np.concatenate(hxy)), 3), axis=0)
    free: list[str] = []
    missing = []
    if len(plan) == 0:
        free += ["shift X", "shift Y"]
    if len(plan) < 2:
        free += ["rotation κ", "scale"]
        missing.append("≥ 2 planimetric control points (shift, rotation κ, scale)")
    if n_h == 0:
        free.append("shift Z")
    if len(heights) >= 3 and _not_collinear(heights):
        pass
    elif len(heights) >= 2:
        free.append("tilt about the line of the height points")
        missing.append("a third height point off the line of the others (tilt)")
    else:
        free += ["tilt ω", "tilt φ"]
        missing.append("≥ 3 non-collinear height control points (height, tilts ω and φ)")
    return free, missing


def _not_collinear(xy: F64) -> bool:
    xy = _finite_rows(xy)
    if xy.shape[0] < 3:
        return False
    c = xy - xy.mean(axis=0)
    sv = np.linalg.svd(c, compute_uv=False)
    return bool(sv.shape[0] >= 2 and sv[1] > 1e-3 * max(sv[0], 1e-12))


def image_condition_deficit(block: Block, setup: PointSetup) -> NDArray[np.int_]:
    """Per image: how many of its 6 orientation parameters its rays cannot determine.

    Hold every other image fixed. A ray of image i to a point that is determined without
    i (fixed, or with its other rays and priors giving ≥ 3 conditions) yields 2
    conditions; a point with one other ray can still slide along that ray (1 unknown
    more), a point with no other ray keeps all three coordinates free (minus priors).
    Observed exterior coordinates add one condition each. If the unknowns
    (6 + the points' remaining freedoms) exceed the conditions, the normal equations of
    the whole block have a null vector: that image moves, those points slide along their
    other rays, nothing else changes. The typical case is an image whose other points
    are check points (their rays do not enter the adjustment): two intersected points and
    one two-ray point give 2 + 2 + 1 = 5 conditions for 6 unknowns.

    Parameters
    ----------
    block : Block
    setup : PointSetup

    Returns
    -------
    ndarray of int, shape (m,)
        Lower bound of the rank defect per image (0 where the count is satisfied; a
        count, not a proof of regularity).
    """
    obs = block.observations
    u = setup.used_obs
    img, pt = obs.image[u], obs.point[u]
    m, p = block.n_images, block.n_points
    rays = np.bincount(pt, minlength=p)
    k = np.isfinite(setup.prior_sigma).sum(axis=1)  # coordinates with a prior
    # freedom of the point for this ray: 3 − priors − 2 × (its rays in other images)
    free = np.where(setup.unknown[pt], np.maximum(0, 3 - k[pt] - 2 * (rays[pt] - 1)), 0)
    unknowns = 6 + np.bincount(img, weights=free, minlength=m)
    img_tab = block.images
    eo = (np.isfinite(img_tab.X0_obs) & np.isfinite(img_tab.X0_sigma)).sum(axis=1)
    eo = eo + (np.isfinite(img_tab.angles_obs) & np.isfinite(img_tab.angles_sigma)).sum(axis=1)
    conditions = 2 * np.bincount(img, minlength=m) + eo
    return np.maximum(0, unknowns - conditions).astype(int)


def check_image_conditions(block: Block, setup: PointSetup) -> None:
    """Raise :class:`NotDeterminableError` for images whose rays leave the orientation free.

    See :func:`image_condition_deficit`. Not applied with auxiliary (GNSS, APR)
    observations, which may supply the missing conditions.
    """
    deficit = image_condition_deficit(block, setup)
    bad = np.flatnonzero(deficit)
    if bad.size:
        ids = [block.images.ids[i] for i in bad[:8]]
        more = f" and {bad.size - 8} more" if bad.size > 8 else ""
        raise NotDeterminableError(
            f"{bad.size} image(s) have fewer conditions than orientation unknowns "
            f"(rays to intersected or control points count 2, to two-ray points 1; rays of "
            f"check points do not enter): {', '.join(ids)}{more}; measure further tie or "
            "control points in them, or use fewer check points there",
            parameters=[f"{i}.X0" for i in ids],
            defect=int(deficit.sum()),
        )


def check_datum(block: Block, setup: PointSetup) -> None:
    """Raise if control and observed centres leave the datum free, or an image is free.

    :class:`NotDeterminableError` from :func:`check_image_conditions` first (the count of
    conditions per image), then :class:`DatumDefectError` if the datum is free (naming
    the planimetric and height control an aerial block lacks; a block that is not aerial
    and has nothing at all — a reconstruction as imported — is told so without heights).
    A block read from a file in model units (``block.meta["units"]["length"]``) is never
    aerial, wherever its cameras look (:func:`orientviz.plausibility.is_aerial`).
    """
    check_image_conditions(block, setup)
    free, missing = _datum_elements(block, setup)
    length = block.meta.get("units", {}).get("length", "m")  # a file's unit (io/kinds/_frame)
    if len(free) == 7 and not is_aerial(block, length):  # nothing given, not flown: no aerial words
        raise DatumDefectError(
            "7 datum parameter(s) are free: add control or fix them — the block has no "
            "control points and no observed projection centres (undetermined: the 3 shifts, "
            "the 3 rotations and the scale)",
            parameters=[f"datum: {f}" for f in free],
            defect=7,
        )
    if free:
        raise DatumDefectError(
            f"{len(free)} datum parameter(s) are free: add control or fix them — missing "
            f"{'; '.join(missing)} (undetermined: {', '.join(free)})",
            parameters=[f"datum: {f}" for f in free],
            defect=len(free),
        )
