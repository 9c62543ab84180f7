"""Geometry that cannot be right, found before an adjustment starts.

A problem file can be valid JSON with valid numbers and still describe a geometry no
camera ever saw: points behind the cameras, rays that meet at a glancing angle, an image
with fewer observations than unknowns, an image coordinate of −1e308 mm or a point a
million block widths away. :func:`check_block` finds these in one vectorised pass over
the block's tables (no loop over images or points) and returns :class:`Finding` records
in the user's ids; :func:`raise_for` turns the fatal ones into the usual exceptions
(``InputError``, exit code 2, for values that cannot be data; ``AdjustmentError``, exit
code 3, for a geometry that cannot give a meaningful adjustment). Warnings are left to
the caller: the command line prints them, the report lists them, and they are logged on
the ``"orientviz"`` logger.

Conventions as everywhere: object space m, Z up; image coordinates mm; the camera looks
along its −z axis (image plane at z = −c), R image → object.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from .block import CONTROL, Block
from .errors import AdjustmentError, InputError
from .rotation import matrix_from_opk
from .units import MODEL_UNIT, length_name

log = logging.getLogger("orientviz")
log.addHandler(logging.NullHandler())  # a library logs; the application decides where to

#: An image coordinate farther than this many half-formats from the principal point
#: cannot be a measurement in that image.
IMAGE_FACTOR: float = 10.0
#: A point or projection centre farther than this many block sizes from the block's
#: median is reported (warning).
EXTENT_FACTOR: float = 100.0
#: ... and beyond this many metres from the median it is not a coordinate (error).
ABSURD_M: float = 1e12
#: Rays of a point that all lie within this angle (degrees) give a weak intersection.
MIN_ANGLE_DEG: float = 2.0
#: At most this many ids are named in one message.
NAMED = 5


@dataclass(frozen=True)
class Finding:
    """One implausible geometry.

    Attributes
    ----------
    level : {"warning", "error"}
        ``"error"``: the adjustment cannot be meaningful (see :func:`raise_for`).
    check : str
        ``"empty"``, ``"image-outside"``, ``"model-control"``, ``"far-away"``, ``"behind"``,
        ``"weak-intersection"``, ``"few-observations"``.
    message : str
        One line in the user's ids, saying what to do.
    count : int
        How many observations, points or images are affected.
    place : str
        Where in the file the first one is (``"observations[12]"``), or ``""``.
    exit_code : int
        2 (bad input) or 3 (adjustment impossible) for errors.
    """

    level: str
    check: str
    message: str
    count: int = 1
    place: str = ""
    exit_code: int = field(default=3)


def _names(ids: list[str], idx: NDArray[np.intp]) -> str:
    shown = ", ".join(repr(ids[int(i)]) for i in idx[:NAMED])
    more = f" and {idx.size - NAMED} more" if idx.size > NAMED else ""
    return shown + more


def _rotations(block: Block) -> NDArray[np.float64]:
    a = block.images.angles
    return matrix_from_opk(a[:, 0], a[:, 1], a[:, 2], block.sequence)


def check_block(
    block: Block,
    *,
    exterior_unknown: bool = True,
    place: Callable[[int], str] | None = None,
    min_angle_deg: float = MIN_ANGLE_DEG,
    length: str = "m",
    pixel_mm: float | None = None,
) -> list[Finding]:
    """Find geometry that cannot be right in a block (vectorised, no adjustment).

    Parameters
    ----------
    block : Block
        Cameras, images (approximate or known orientation), points, observations (mm, m,
        rad). NaN values (not yet approximated) are skipped.
    exterior_unknown : bool
        Whether the images' orientations are unknowns (block, resection) or given
        (intersection); only then is the number of observations per image checked.
    place : callable, optional
        ``place(k) -> "observations[k]"``: how the file names observation ``k``.
    min_angle_deg : float
        Rays of a tie or check point all within this angle (degrees) are reported.
    length : str
        The file's length unit, for the messages (``"model"``: a reconstruction's
        arbitrary scale, named "model units"; the block's lengths are read 1 : 1).
    pixel_mm : float, optional
        mm per pixel of a file whose image coordinates are pixels: the messages give
        image coordinates in px (default: mm).

    Returns
    -------
    list of Finding
        Errors first, then warnings.
    """
    place = place or (lambda k: f"observation {k}")
    out: list[Finding] = []
    obs, im, pts, cams = block.observations, block.images, block.points, block.cameras
    n_obs = obs.image.size
    empty = [what for what, n in (("images", len(im.ids)), ("points", len(pts.ids)),
                                  ("observations", n_obs)) if n == 0]  # fmt: skip
    if empty:  # nothing to check or adjust (not a datum defect)
        where = "images" if "images" in empty else empty[0]
        return [Finding("error", "empty", f"nothing to adjust: the file has no "
                        f"{' and no '.join(empty)} (0 rows)", 1, where, exit_code=2)]  # fmt: skip
    cam = im.camera[obs.image] if n_obs else np.zeros(0, dtype=np.intp)
    with np.errstate(all="ignore"):
        # --- image coordinates beyond the image ------------------------------------
        half = np.nanmax(np.column_stack([cams.format_mm / 2, cams.c[:, None]]), axis=1)
        half = np.where(np.isfinite(half) & (half > 0), half, 115.0)
        dx = obs.xy - np.column_stack([cams.x0, cams.y0])[cam]
        outside = np.flatnonzero(np.any(~(np.abs(dx) <= IMAGE_FACTOR * half[cam, None]), axis=1))
        if outside.size:
            k = int(outside[0])
            axis = "x" if not abs(dx[k, 0]) <= IMAGE_FACTOR * half[cam[k]] else "y"
            value = obs.xy[k, 0 if axis == "x" else 1]
            # a pixel file's own numbers (y down) and unit; else mm
            f, iu = (1.0 / pixel_mm, "px") if pixel_mm else (1.0, "mm")
            value = value * f * (-1.0 if pixel_mm and axis == "y" else 1.0)
            out.append(
                Finding(
                    "error",
                    "image-outside",
                    f"{axis} = {value:.6g} {iu} of point {pts.ids[obs.point[k]]!r} in image "
                    f"{im.ids[obs.image[k]]!r} lies far outside the image (half format "
                    f"{half[cam[k]] * f:.6g} {iu}); correct the value or its unit"
                    + (f" ({outside.size} such observations)" if outside.size > 1 else ""),
                    outside.size,
                    place(k),
                    2,
                )
            )
        # --- control in a file without scale -----------------------------------------
        n_ctl = int(np.sum(pts.role == CONTROL))
        if length == MODEL_UNIT and n_ctl:
            out.append(
                Finding(
                    "warning",
                    "model-control",
                    f"{n_ctl} control point(s) in a file whose lengths are model units (the "
                    "arbitrary scale of a reconstruction): their coordinates are read in model "
                    'units too; if they are metric, give the file "length": "m"',
                    n_ctl,
                    "units.length",
                )
            )
        # --- coordinates far from the block -----------------------------------------
        xyz = np.where(np.isfinite(pts.xyz_known), pts.xyz_known, pts.xyz)
        allc = np.concatenate([xyz, im.X0])
        fin = np.all(np.isfinite(allc), axis=1)
        if fin.sum() >= 2:
            centre = np.median(allc[fin], axis=0)
            lo, hi = np.percentile(allc[fin], [10, 90], axis=0)
            size = max(float(np.max(hi - lo)), 1.0)
            unit = length_name(length)
            dist = np.max(np.abs(allc - centre), axis=1)
            far = np.flatnonzero(fin & (dist > EXTENT_FACTOR * size))
            far = far[np.argsort(-dist[far], kind="stable")]  # the farthest named first
            if far.size:
                absurd = bool(np.any(dist[far] > ABSURD_M))
                n_p = pts.ids.__len__()
                names = [f"point {pts.ids[i]!r}" if i < n_p else f"image {im.ids[i - n_p]!r}"
                         for i in far[:NAMED].tolist()]  # fmt: skip
                more = f" and {far.size - NAMED} more" if far.size > NAMED else ""
                out.append(
                    Finding(
                        "error" if absurd else "warning",
                        "far-away",
                        f"{', '.join(names)}{more} {'lies' if far.size == 1 else 'lie'} up to {dist[far[0]]:.3g} {unit} from "
                        f"the block's centre, far outside its extent of about {size:.3g} "
                        f"{unit}; check the coordinates and their unit",
                        far.size,
                        "",
                        2,
                    )
                )
        if n_obs == 0:
            return _sorted(out)
        R = _rotations(block)
        # --- points behind the camera -----------------------------------------------
        d = np.einsum("nji,nj->ni", R[obs.image], xyz[obs.point] - im.X0[obs.image])
        known = np.isfinite(d[:, 2])
        behind = known & (d[:, 2] >= 0)
        if behind.any():
            n_b, n_k = int(behind.sum()), int(known.sum())
            imgs = np.unique(obs.image[behind])
            fatal = n_b * 2 > n_k
            out.append(
                Finding(
                    "error" if fatal else "warning",
                    "behind",
                    f"{n_b} of {n_k} rays have their point behind the camera (images "
                    f"{_names(im.ids, imgs)}): the camera looks along its −z axis"
                    + (
                        "; check the heights, the flying height and the angles (Z up)"
                        if length != MODEL_UNIT and _aerial(R)
                        else "; check the angles of those images and the points' coordinates"
                    ),
                    n_b,
                    place(int(np.flatnonzero(behind)[0])),
                    3,
                )
            )
        # --- fewer observations than unknowns per image ----------------------------
        if exterior_unknown:
            rays = np.bincount(obs.image, minlength=len(im.ids))
            extra = np.sum(np.isfinite(im.X0_obs), axis=1) + np.sum(
                np.isfinite(im.angles_obs), axis=1
            )
            few = np.flatnonzero(2 * rays + extra < 6)
            if few.size:
                i = int(few[0])
                out.append(
                    Finding(
                        "error",
                        "few-observations",
                        f"image(s) {_names(im.ids, few)} have fewer observations than the 6 "
                        f"unknowns of an orientation (image {im.ids[i]!r}: {rays[i]} points = "
                        f"{2 * rays[i] + extra[i]} observations); measure at least 3 points "
                        "in every image or remove it",
                        few.size,
                        "",
                        3,
                    )
                )
        # --- weak intersections ------------------------------------------------------
        ray = np.einsum(
            "nij,nj->ni",
            R[obs.image],
            np.column_stack([dx, -np.broadcast_to(cams.c[cam], (n_obs,))]),
        )
        ray /= np.linalg.norm(ray, axis=1, keepdims=True)
        use = np.all(np.isfinite(ray), axis=1) & (pts.role[obs.point] != CONTROL)
        p = obs.point[use]
        n_p = len(pts.ids)
        count = np.bincount(p, minlength=n_p)
        mean = np.column_stack(
            [np.bincount(p, ray[use, k], minlength=n_p) for k in range(3)]
        ).astype(float)
        mean /= np.linalg.norm(mean, axis=1, keepdims=True)
        cos = np.einsum("ni,ni->n", ray[use], mean[p])
        min_cos = np.ones(n_p)
        np.minimum.at(min_cos, p, cos)
        # the largest angle between two rays is at most twice the largest angle to the mean
        spread = 2 * np.degrees(np.arccos(np.clip(min_cos, -1.0, 1.0)))
        weak = np.flatnonzero((count >= 2) & (spread < min_angle_deg))
        if weak.size:
            out.append(
                Finding(
                    "warning",
                    "weak-intersection",
                    f"{weak.size} point(s) ({_names(pts.ids, weak)}) are seen by rays that meet "
                    f"at less than {min_angle_deg:g}°: their position along the rays is "
                    "hardly determined; add images with a longer base",
                    weak.size,
                )
            )
    return _sorted(out)


#: A block is aerial when at least this share of its images looks down (within 45° of −Z).
AERIAL_SHARE: float = 0.8


def is_aerial(block: Block, length: str = "m") -> bool:
    """Whether messages about ``block`` may speak of heights, flying height and Z up.

    True when its frame has a real length unit (not the ``"model"`` units of a
    reconstruction, whose axes point anywhere) and at least :data:`AERIAL_SHARE` of its
    images look down (viewing direction within 45° of −Z).
    """
    if length == MODEL_UNIT or block.n_images == 0:
        return False
    with np.errstate(all="ignore"):
        return _aerial(_rotations(block))


def _aerial(R: np.ndarray) -> bool:
    """Whether most images look down (viewing direction −z of the image within 45° of
    −Z): the block is aerial, and messages may speak of heights and flying height."""
    down = R[:, 2, 2]  # −(Z component of the viewing direction R·(0, 0, −1))
    fin = np.isfinite(down)
    return bool(fin.any() and np.mean(down[fin] > np.cos(np.pi / 4)) >= AERIAL_SHARE)


def check_magnitudes(data: object, limit: float = ABSURD_M) -> list[Finding]:
    """Numbers beyond ± ``limit`` in the float arrays of a non-frame problem's data.

    Looks at the data object's attributes and one level below (e.g. a similarity's
    ``source.xyz``); NaN (not given) is ignored. Returns errors (exit code 2).
    """
    out = []
    for name, value in vars(data).items():
        inner = vars(value).items() if hasattr(value, "__dict__") else [("", value)]
        for sub, arr in inner:
            if not isinstance(arr, np.ndarray) or arr.dtype.kind != "f":
                continue
            with np.errstate(invalid="ignore"):
                big = np.flatnonzero(np.abs(arr.reshape(-1)) > limit)
            if big.size:
                what = f"{name}.{sub}" if sub else name
                out.append(
                    Finding(
                        "error",
                        "far-away",
                        f"a value of {arr.reshape(-1)[big[0]]:.3g} in {what}: beyond ±{limit:g} "
                        "(m, mm or rad); check the value and its unit",
                        big.size,
                        "",
                        2,
                    )
                )
    return out


def _sorted(findings: list[Finding]) -> list[Finding]:
    return sorted(findings, key=lambda f: (f.level != "error", f.exit_code == 3))


def raise_for(findings: list[Finding], source: str | None) -> list[Finding]:
    """Raise the first error (exit 2 as InputError, 3 as AdjustmentError); log and return
    the warnings."""
    for f in findings:
        if f.level != "error":
            continue
        if f.exit_code == 2:
            raise InputError(f.message, source, f.place or None)
        raise AdjustmentError(f.message)
    warnings = [f for f in findings if f.level == "warning"]
    for f in warnings:
        log.warning("%s: %s", source or "block", f.message)
    return warnings
