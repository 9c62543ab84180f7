"""The camera models of a problem file's ``cameras[]`` (kind ``block``).

A camera row may say what the bundle estimates of it::

    {"id": "C4040Z", "c": 2337.6, "x0": 1136, "y0": 852, "format": [2272, 1704],
     "model": "backward", "free": ["c", "x0", "y0", "as", "K1", "K2", "K3", "P1", "P2"],
     "sigma": {"sk": 1e-4}, "K1": 0.0}

* ``model``: ``"backward"`` (photogrammetry: DBAT, PhotoModeler — the distortion of the
  measured point; terms as, sk, K1–K3, P1, P2) or ``"forward"`` (computer vision: OpenCV
  — the distortion of the ideal point; terms as, sk, k1–k3, p1, p2), the camera model
  inside the bundle's projection (:class:`orientviz.bundle.LensModel`).
* each parameter (c, x0, y0 and the terms) is **free** (listed in ``free``; default all
  but sk), **weighted** (a prior σ in ``sigma``: an observation of its given value) or
  **fixed** (neither) at its given value (the row's c, x0, y0 and terms; terms default 0).
* ``additional``: instead of a model, an additional-parameter set (``"ebner12"``,
  ``"gruen44"``, ``"brown"``: corrections at the observed coordinates in µm, one group
  per camera), its parameters free (``free``), weighted (``sigma`` in µm, or
  ``additional_sigma`` for all) or fixed at 0 (not in ``free`` when ``free`` is given).

Units: c, x0, y0, their σ and ``r0`` in the file's image unit; the lens terms in the
photogrammetric image frame (y up) and mm (backward K1 mm⁻², K2 mm⁻⁴, K3 mm⁻⁶, P1, P2
mm⁻¹ as DBAT and PhotoModeler print them; forward terms unitless, OpenCV's p1 with the
opposite sign because OpenCV's y points down), whatever ``units.image`` is.

:func:`read_camera_models` gives each row's spec in internal units; the block carries
them (``block.cameras.model``) and :func:`orientviz.bundle.bundle_adjust` estimates
what they state (:mod:`orientviz.bundle._block_cameras`), in the library as in
``orientviz solve``.
"""

from __future__ import annotations

from typing import Any

from ..problem import Units
from ..tables import Table

#: The lens terms a camera row may give (both models).
TERMS = ("as", "sk", "K1", "K2", "K3", "P1", "P2", "k1", "k2", "k3", "p1", "p2")
#: Fields of a camera row about its model (default None).
MODEL_FIELDS = {k: None for k in ("model", "free", "sigma", "r0", "additional",
                                  "additional_sigma") + TERMS}  # fmt: skip
_IO = ("c", "x0", "y0")


def _names(model: str) -> tuple[str, ...]:
    """The parameter names of the ``"backward"`` or ``"forward"`` lens model."""
    from ...bundle.model import BACKWARD_NAMES, FORWARD_NAMES  # SciPy only for lens models

    return {"backward": BACKWARD_NAMES, "forward": FORWARD_NAMES}[model]


def _other(name: str, model: str) -> str:
    mine = ", ".join(_names(model)[3:])
    return f"{name!r} is not a term of the {model} model (its terms: {mine})"


def read_camera_models(t: Table, units: Units) -> list[dict[str, Any]]:
    """Per camera row its model spec in internal units ({} = none); fails at the cell.

    A spec: ``{"model": kind, "free": [...], "sigma": {name: σ}, "values": {term: v},
    "r0": mm or None}`` or ``{"additional": name, "additional_sigma": µm or None}``.
    """
    I = units.mm_per_image
    col = t.columns
    out: list[dict[str, Any]] = []
    for i in range(t.n):
        model, add = col["model"][i], col["additional"][i]
        terms = {k: col[k][i] for k in TERMS if col[k][i] is not None}
        if model is not None and add is not None:
            raise t.fail(i, "additional", 'give "model" or "additional", not both')
        if model is None:
            fields = ("r0",) + tuple(terms) + (("free", "sigma") if add is None else ())
            for field in fields:
                if col[field][i] is not None:
                    raise t.fail(i, field, 'needs "model": "backward" or "forward"')
            if col["additional_sigma"][i] is not None and add is None:
                raise t.fail(i, "additional_sigma", 'needs "additional" (ebner12, gruen44, brown)')
            out.append({} if add is None else _additional_spec(t, i, add))
            continue
        if col["additional_sigma"][i] is not None:
            raise t.fail(i, "additional_sigma", 'needs "additional" (ebner12, gruen44, brown)')
        names = _names(model)
        for k in terms:
            if k not in names:
                raise t.fail(i, k, _other(k, model))
        free = col["free"][i]
        for k in free or ():
            if k not in names:
                raise t.fail(i, "free", _other(k, model))
        sigma = dict(col["sigma"][i] or {})
        for k, s in sigma.items():
            if k not in names:
                raise t.fail(i, "sigma", _other(k, model))
            if free and k in free:
                raise t.fail(i, "sigma", f"{k!r} is listed in free and has a prior σ: give one")
            if k in _IO:
                sigma[k] = float(s) * I
        r0 = col["r0"][i]
        out.append({
            "model": model,
            "free": None if free is None else [str(k) for k in free],
            "sigma": sigma,
            "values": {k: float(v) for k, v in terms.items()},
            "r0": None if r0 is None else float(r0) * I,
        })  # fmt: skip
    return out


def _additional_spec(t: Table, i: int, add: str) -> dict[str, Any]:
    """An additional-parameter set of camera row ``i`` with its free/weighted/fixed parameters."""
    from ...bundle import ap_set  # the bundle (SciPy) only when a file names a set

    col = t.columns
    names = list(ap_set(add).names)
    free, sigma = col["free"][i], dict(col["sigma"][i] or {})
    for field, keys in (("free", free or ()), ("sigma", sigma)):
        for k in keys:
            if k not in names:
                raise t.fail(i, field, f"{k!r} is not a parameter of {add} (its parameters: "
                             f"{', '.join(names[:12])}{' …' if len(names) > 12 else ''})")  # fmt: skip
            if field == "sigma" and free and k in free:
                raise t.fail(i, "sigma", f"{k!r} is listed in free and has a prior σ: give one")
    return {"additional": add, "additional_sigma": col["additional_sigma"][i],
            "free": None if free is None else [str(k) for k in free], "sigma": sigma}  # fmt: skip


def camera_model_cells(models: list[dict[str, Any]], units: Units) -> dict[str, list[Any]]:
    """The model columns of the cameras table in ``units`` (inverse of the reader)."""
    I = units.mm_per_image
    cols: dict[str, list[Any]] = {k: [] for k in MODEL_FIELDS}
    for spec in models:
        for k in MODEL_FIELDS:
            v = spec.get(k)
            if k in TERMS:
                v = spec.get("values", {}).get(k)
            elif k == "sigma" and v:
                v = {n: (s / I if n in _IO else s) for n, s in v.items()}
            elif k == "r0" and v is not None:
                v = v / I
            cols[k].append(v)
    return {k: v for k, v in cols.items() if any(x is not None and x != {} for x in v)}


def camera_notes(block, adj, units: Units) -> list[str]:
    """Report lines of the estimated cameras: value ± σ per parameter (c, x0, y0 in the
    file's image unit, the terms as in the file), and the high correlations."""
    cam = getattr(adj, "camera", None)
    if cam is None:
        return []
    I, Y = units.mm_per_image, units.mm_per_image * units.y_sign
    scale = {"c": I, "x0": I, "y0": Y}
    lines = []
    for g in range(cam.value.shape[0]):
        cid = block.cameras.ids[g] if g < len(block.cameras.ids) else f"group {g}"
        parts = []
        for j, name in enumerate(cam.names):
            f = scale.get(name, 1.0)
            unit = units.image if name in scale else cam.units[j]
            unit = "" if unit in ("", "1") else f" {unit}"  # a pure number is printed bare
            if cam.estimated[j]:
                parts.append(
                    f"{name} {cam.value[g, j] / f + 0.0:.7g} ± {cam.sigma[g, j] / abs(f):.2g}{unit}"
                )
            else:
                parts.append(f"{name} {cam.value[g, j] / f + 0.0:.7g} (fixed)")  # + 0.0: no "-0"
        lines.append(f"camera {cid} ({cam.kind} model): " + ", ".join(parts))
    pairs = cam.high_correlations(0.9)
    if pairs:
        lines.append("camera parameters correlated above 0.9: " + ", ".join(
            f"{a}~{b} ρ = {r:+.2f}" for _, a, b, r in pairs))  # fmt: skip
    return lines


def camera_parameters(block, adj, units: Units) -> list:
    """The estimated cameras as report parameters (``Solution.parameters``): c, x0, y0 as
    image quantities (y0 in the file's frame: pixels count downwards), the terms as
    pure numbers in their own units (named ``"<camera>.K1 [mm⁻²]"``); fixed ones left out."""
    from ..solution import Parameter  # a solution's types: only when solving

    cam = getattr(adj, "camera", None)
    if cam is None:
        return []
    out = []
    for g in range(cam.value.shape[0]):
        cid = block.cameras.ids[g] if g < len(block.cameras.ids) else f"group{g}"
        for j, name in enumerate(cam.names):
            if not cam.estimated[j]:
                continue
            v, s = float(cam.value[g, j]), float(cam.sigma[g, j])
            if name in _IO:
                v = v * (units.y_sign if name == "y0" else 1.0)
                out.append(Parameter(f"{cid}.{name}", v, s, "image"))
            else:
                unit = "" if cam.units[j] == "1" else f" [{cam.units[j]}]"
                out.append(Parameter(f"{cid}.{name}{unit}", v, s, "1"))
    return out
