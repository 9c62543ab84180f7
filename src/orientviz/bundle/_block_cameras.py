"""What a block's cameras say the bundle estimates of them: ``block.cameras.model``.

A block read from a problem file (or imported from COLMAP, BAL, DBAT) may carry per
camera a lens model or an additional-parameter set (``Cameras.model``, one dict per
camera, ``{}`` = nothing):

* a lens model: ``{"model": "backward" | "forward", "free": [names] or None,
  "sigma": {name: σ}, "values": {term: value}, "r0": mm or None}`` — c, x0, y0 and the
  terms of :class:`~orientviz.bundle.LensModel` (σ of c, x0, y0 in mm, the terms in
  their own units);
* an additional-parameter set: ``{"additional": "ebner12" | "gruen44" | "brown",
  "additional_sigma": µm or None, "free": [names] or None, "sigma": {name: µm}}``.

:func:`block_camera_options` turns them into the keywords ``additional``, ``ap_group``
(one group per camera) and ``ap_sigma`` of :func:`~orientviz.bundle.bundle_adjust`;
:func:`camera_keywords` is how :func:`~orientviz.bundle.bundle_adjust` applies them:
keywords given by the caller win over the block's models. The problem file's
``cameras[]`` rows are read into these dicts by :mod:`orientviz.io.kinds._cameras`.

A lens model that estimates nothing and whose every term (as, sk, the distortion) is 0
at the cameras' own c, x0, y0 predicts f = (x0, y0) + c·n, the plain collinearity
equations (e.g. a COLMAP PINHOLE camera read with ``lens="fixed"``):
:func:`held_plain_camera` recognises it, and :func:`~orientviz.bundle.bundle_adjust`
then runs the plain model and reports the held camera as the lens path would.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..block import Block
from ..errors import InputError
from .model import BoundLens, LensModel

#: σ (µm) that holds a fixed additional parameter at 0.
FIXED_SIGMA_UM = 1e-6


def additional_sigmas(spec: dict[str, Any], names: list[str]) -> np.ndarray:
    """σ (µm) of the pseudo-observations p = 0 of each parameter of an additional set.

    Its ``sigma`` if given; with ``free``, inf (free) for the listed and
    :data:`FIXED_SIGMA_UM` (held at 0) for the others; else ``additional_sigma`` or inf.
    """
    sig, free = spec.get("sigma") or {}, spec.get("free")
    default = spec.get("additional_sigma")
    out = []
    for k in names:
        if k in sig:
            out.append(float(sig[k]))
        elif free is not None:
            out.append(np.inf if k in free else FIXED_SIGMA_UM)
        else:
            out.append(np.inf if default is None else float(default))
    return np.array(out)


def block_camera_options(block: Block) -> dict[str, Any]:
    """:func:`~orientviz.bundle.bundle_adjust` keywords for the block's camera models.

    Parameters
    ----------
    block : Block
        Its ``cameras.model`` (see the module docstring); every camera must state the
        same model (kind, free and weighted parameters) or the same additional-parameter
        set; each camera is its own parameter group (``ap_group`` = ``images.camera``).

    Returns
    -------
    dict
        ``{}`` when no camera states a model; else ``additional`` (a
        :class:`~orientviz.bundle.LensModel` with the cameras' values, or the named set)
        and ``ap_group``, with a set also ``ap_sigma`` (µm).

    Raises
    ------
    InputError
        If the cameras state different models.
    """
    models = list(getattr(block.cameras, "model", None) or [])
    if not any(models):
        return {}
    ids = block.cameras.ids
    first = models[0]
    key = _shape(first)
    for cid, spec in zip(ids, models):
        if _shape(spec) != key:
            raise InputError(
                f"camera {cid!r}: every camera of a block must state the same model "
                f"({_describe(first)} for camera {ids[0]!r}, {_describe(spec)} here)"
            )
    group = np.asarray(block.images.camera, np.int64)
    if "additional" in first:
        cam = block.cameras
        opts = {"b": float(np.min(cam.format_mm[0])) * 0.4} if first["additional"] != "brown" else {
            "c": float(cam.c[0]), "r0": float(np.hypot(*cam.format_mm[0])) / 4}  # fmt: skip
        from .model import ap_set  # the additional-parameter sets: only when a camera names one

        aps = ap_set(first["additional"], **opts)
        return {"additional": aps, "ap_group": group,
                "ap_sigma": additional_sigmas(first, list(aps.names))}  # fmt: skip
    values = {}
    for k in sorted({k for s in models for k in s["values"]}):
        values[k] = [s["values"].get(k, 0.0) for s in models]
    free = first["free"]
    model = LensModel(first["model"], free=None if free is None else tuple(free),
                      prior=dict(first["sigma"]), values=values,
                      r0=first["r0"])  # fmt: skip
    return {"additional": model, "ap_group": group}


def camera_keywords(block: Block, additional: Any, ap_group: Any, ap_sigma: Any) -> tuple:
    """``(additional, ap_group, ap_sigma)`` for a bundle run of ``block``.

    ``additional`` given: the caller's three keywords as they are (the block's models
    are not read). ``additional=False``: no additional parameters, whatever the cameras
    state. ``additional=None``: the block's camera models
    (:func:`block_camera_options`), with ``ap_group`` / ``ap_sigma`` replaced where the
    caller gave them.
    """
    if additional is False:
        return None, ap_group, ap_sigma
    if additional is not None:
        return additional, ap_group, ap_sigma
    opts = block_camera_options(block)
    if not opts:
        return None, ap_group, ap_sigma
    return (
        opts["additional"],
        opts["ap_group"] if ap_group is None else ap_group,
        opts.get("ap_sigma") if ap_sigma is None else ap_sigma,
    )


def held_plain_camera(
    block: Block, additional: Any, ap_group: Any, used_obs: np.ndarray
) -> BoundLens | None:
    """``additional`` bound to the block if it is exactly the plain collinearity model.

    That is a :class:`~orientviz.bundle.LensModel` (either kind) that estimates no
    parameter (none free, none with a prior), whose given as, sk and distortion terms
    are 0 in every group, and whose c, x0, y0 (mm) are those of each image's own
    camera: its projection f = (x0, y0) + c·n is the one of the plain model.

    Parameters
    ----------
    block : Block
        The block to adjust.
    additional : object
        The bundle's ``additional`` (after :func:`camera_keywords`).
    ap_group : array_like of int, shape (m,), optional
        Parameter group of each image (default: one per camera, as for any lens model).
    used_obs : ndarray of bool, shape (n,)
        The rays that enter the adjustment (they give the reference radius ``r0`` of
        :meth:`~orientviz.bundle.LensModel.bind`, as in the lens model's own run).

    Returns
    -------
    BoundLens or None
        The bound model (its :meth:`~orientviz.bundle.model.BoundLens.estimates` at no
        correction is the held camera the lens path reports), or None if ``additional``
        is anything else.
    """
    if not isinstance(additional, LensModel) or additional.names:
        return None
    group = block.images.camera if ap_group is None else np.asarray(ap_group, np.int64)
    if group.shape != (block.n_images,) or group.size == 0 or group.min() < 0:
        return None  # the lens path reports the error
    obs = block.observations
    used = np.flatnonzero(used_obs)
    try:
        bound = additional.bind(block, obs.xy[used], obs.image[used], group)
    except InputError:
        return None  # the lens path reports it
    th = bound.theta0
    cams = block.cameras
    cam = block.images.camera
    own = np.column_stack([cams.c[cam], cams.x0[cam], cams.y0[cam]])
    if np.any(th[:, 3:] != 0.0) or not np.array_equal(th[group, :3], own):
        return None
    return bound


def _shape(spec: dict[str, Any]) -> tuple:
    if "additional" in spec:
        free = None if spec.get("free") is None else tuple(spec["free"])
        return ("additional", spec["additional"], spec.get("additional_sigma"), free,
                tuple(sorted((spec.get("sigma") or {}).items())))  # fmt: skip
    if not spec:
        return ("none",)
    free = None if spec["free"] is None else tuple(spec["free"])
    return ("model", spec["model"], free, tuple(sorted(spec["sigma"].items())))


def _describe(spec: dict[str, Any]) -> str:
    if not spec:
        return "no model"
    if "additional" in spec:
        return f"additional {spec['additional']!r}"
    return f"model {spec['model']!r} free {spec['free']} sigma {spec['sigma']}"
