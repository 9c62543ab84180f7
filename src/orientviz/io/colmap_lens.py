"""COLMAP's cameras as orientviz's forward lens model, and tracks as COLMAP writes them.

COLMAP's objective is the reprojection error in *distorted* pixels. An imported model
keeps it: the observations stay COLMAP's pixels (``units.image = "px"``: x = u·p,
y = −v·p mm from the upper-left corner, p the nominal pixel size) and each camera
becomes the forward model of :mod:`orientviz.bundle._lens` (the distortion of the ideal
point, as OpenCV and COLMAP define it). With COLMAP's camera frame (x right, y down,
z forward) and orientviz's (y up, viewing along −z) the parameters map exactly:

    c = fy·p,  as = fx/fy − 1,  x0 = cx·p,  y0 = −cy·p,  k1, k2, p2 as COLMAP's,
    p1 = −p1_COLMAP (OpenCV's y points down),

for SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL (k → k1), RADIAL and OPENCV. What COLMAP's
bundle adjuster refines by default (focal length and distortion, not the principal
point) is free with ``lens="refine"`` (:data:`FREE_TERMS`); ``"fixed"`` holds the
cameras. σ of an image coordinate is σ_px·p in both coordinates, so σ̂0 reads as the
pixel RMS a COLMAP user knows (with σ_px = 1).

Tracks: COLMAP may match one 3D point to two keypoints of one image (often SIFT's two
orientations at one location). A problem file holds one observation per image and
point, so :func:`repeated_observations` keeps the first keypoint (lowest POINT2D_IDX,
the order COLMAP writes) and leaves the others out; the importer says how many and how
far they lay from the kept one. COLMAP itself would use both.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError
from .colmap_text import CAMERA_MODELS

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: The forward model's terms COLMAP's bundle adjuster refines by default, per camera model
#: (focal length(s) and distortion; the principal point stays).
FREE_TERMS: dict[str, tuple[str, ...]] = {
    "SIMPLE_PINHOLE": ("c",),
    "PINHOLE": ("c", "as"),
    "SIMPLE_RADIAL": ("c", "k1"),
    "RADIAL": ("c", "k1", "k2"),
    "OPENCV": ("c", "as", "k1", "k2", "p1", "p2"),
}
#: ``lens`` of :func:`orientviz.io.colmap.read_colmap`.
LENS_MODES = ("refine", "fixed", "undistort")


def forward_camera(model: str, params: dict[str, float], pixel_mm: float, lens: str):
    """c, x0, y0 (mm) and the lens spec (``cameras.model`` entry) of one COLMAP camera.

    ``params`` by COLMAP's names (f or fx, fy; cx, cy; k or k1, k2; p1, p2), px.
    """
    fx, fy = params.get("fx", params.get("f")), params.get("fy", params.get("f"))
    values = {"as": fx / fy - 1.0}
    values["k1"] = params.get("k", params.get("k1", 0.0))
    values["k2"] = params.get("k2", 0.0)
    values["p1"] = -params.get("p1", 0.0)
    values["p2"] = params.get("p2", 0.0)
    values = {k: float(v) for k, v in values.items() if v != 0.0 or k in FREE_TERMS[model]}
    free = list(FREE_TERMS[model]) if lens == "refine" else []
    spec: dict[str, Any] = {"model": "forward", "free": free, "sigma": {}, "values": values,
                            "r0": None}  # fmt: skip
    return fy * pixel_mm, params["cx"] * pixel_mm, -params["cy"] * pixel_mm, spec


def colmap_model_of(values: dict) -> str:
    """The smallest COLMAP camera model that holds the terms a forward camera names (zero
    or not: :func:`forward_camera` names those of its COLMAP model)."""
    terms = {k for k in values if k in FREE_TERMS["OPENCV"]}
    for model in ("SIMPLE_PINHOLE", "PINHOLE", "SIMPLE_RADIAL", "RADIAL", "OPENCV"):
        if terms <= set(FREE_TERMS[model]):
            return model
    return "OPENCV"


def colmap_params(model: str, c: float, x0: float, y0: float, values: dict, pixel_mm: float):
    """COLMAP's parameters (px, in COLMAP's order) of a forward camera: the inverse of
    :func:`forward_camera`. Terms the COLMAP model cannot hold must be 0."""
    fy = c / pixel_mm
    fx = fy * (1.0 + values.get("as", 0.0))
    named = {"f": fy, "fx": fx, "fy": fy, "cx": x0 / pixel_mm, "cy": -y0 / pixel_mm,
             "k": values.get("k1", 0.0), "k1": values.get("k1", 0.0),
             "k2": values.get("k2", 0.0), "p1": -values.get("p1", 0.0),
             "p2": values.get("p2", 0.0)}  # fmt: skip
    names = CAMERA_MODELS[model][1]
    held = {"as": "fx" in names, "k1": "k" in names or "k1" in names, "k2": "k2" in names,
            "p1": "p1" in names, "p2": "p2" in names}  # fmt: skip
    for term, ok in held.items():
        if not ok and values.get(term, 0.0) != 0.0:
            raise InputError(f"a {model} camera has no {term} (value {values[term]:g})")
    for term in ("sk", "k3"):
        if values.get(term, 0.0) != 0.0:
            raise InputError(f"COLMAP's {model} camera has no {term}")
    if model in ("SIMPLE_PINHOLE", "SIMPLE_RADIAL", "RADIAL") and fx != fy:
        raise InputError(f"a {model} camera has one focal length (fx = {fx:g}, fy = {fy:g})")
    return [named[n] for n in names]


def repeated_observations(obs_image: I64, obs_point: I64, uv: F64) -> tuple[I64, float]:
    """Indices of the observations to keep (each (image, point) pair once: the first) and
    the largest distance (px) of a left-out keypoint from the kept one (0 if none)."""
    n_pt = int(obs_point.max()) + 1 if obs_point.size else 1
    pair = obs_image.astype(np.int64) * n_pt + obs_point
    order = np.argsort(pair, kind="stable")
    again = np.zeros(pair.size, bool)
    again[order[1:]] = pair[order[1:]] == pair[order[:-1]]
    if not again.any():
        return np.arange(pair.size), 0.0
    # the kept one of each repeated pair: the first of its run in the sorted order
    run_start = np.r_[True, pair[order[1:]] != pair[order[:-1]]]
    first = order[np.maximum.accumulate(np.where(run_start, np.arange(pair.size), 0))]
    lead = np.empty(pair.size, np.int64)
    lead[order] = first
    gone = np.flatnonzero(again)
    far = float(np.max(np.linalg.norm(uv[gone] - uv[lead[gone]], axis=1)))
    return np.flatnonzero(~again), far
