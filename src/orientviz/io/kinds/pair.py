"""Kind ``pair``: relative orientation of a stereo pair from homologous image points.

The file gives, per point, the image coordinates in the left (``xl``, ``yl``) and right
(``xr``, ``yr``) photograph in ``units.image``, reduced to the principal point, and the
principal distance ``camera.c``. The five elements of a dependent pair (``by``, ``bz``,
``omega``, ``phi``, ``kappa`` of the right image, the left one fixed) or an independent
pair (``phi1``, ``kappa1``, ``phi2``, ``omega2``, ``kappa2``) are estimated from the
rigorous y-parallaxes (``options.method``: ``"parallax"``, Kovarik's estimator, the
default), from all image coordinates with the model points unknown (``"collinearity"``)
or from one coplanarity condition per point (``"coplanarity"``); angles in the file's
``sequence``. Model lengths (the base, by, bz, the model points, the parallaxes, the
triple products and their σ) are in ``units.length``; the model base defaults to the
median x-parallax (``options.base = "mean"``: the mean), i.e. the model at image scale.

Solvers: :func:`orientviz.orientation.relative.relative_orientation` and, with
``options.route = "essential"``, :func:`orientviz.orientation.essential.essential_route`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...adjust.result import W_CRITICAL
from ...errors import InputError
from ...orientation.essential import essential_route
from ...orientation.relative import DEPENDENT, INDEPENDENT, relative_orientation
from ..problem import Problem, Units
from ..registry import Kind, register_kind
from ..solution import Parameter, Solution
from ..tables import REQUIRED, json_number, json_numbers, read_table, write_table

F64 = NDArray[np.float64]
FIELDS = {"id": REQUIRED, "xl": REQUIRED, "yl": REQUIRED, "xr": REQUIRED, "yr": REQUIRED}
LENGTHS = ("by", "bz")


@dataclass
class PairData:
    """A pair problem in internal units: image mm, model lengths m, angles rad."""

    ids: list[str]
    xy_left: F64
    xy_right: F64
    c: float
    approx: dict[str, float] = field(default_factory=dict)
    sequence: str = "opk"


def load(doc: dict[str, Any], units: Units, source: str) -> PairData:
    """Read a ``pair`` document (image coordinates in mm, approximations in m and rad)."""
    t = read_table(doc, "points", FIELDS, source)
    t.index("id", "point")
    k = units.mm_per_image
    xy1 = np.column_stack([t.floats("xl", k), t.floats("yl", k)])
    xy2 = np.column_stack([t.floats("xr", k), t.floats("yr", k)])
    if t.n < 5:
        raise InputError(
            f"a relative orientation needs at least 5 points, got {t.n}", source, "points"
        )
    approx = {}
    for name, v in doc.get("approx", {}).items():
        approx[name] = float(v) * (units.m_per_length if name in LENGTHS else units.rad_per_angle)
    elements = (doc.get("options") or {}).get("elements", "dependent")

    allowed = DEPENDENT if elements == "dependent" else INDEPENDENT
    for name in approx:
        if name not in allowed:
            raise InputError(
                f"approximation {name!r} is not an element of a {elements} pair",
                source,
                f"approx.{name}",
            )
    return PairData(
        t.strings("id"), xy1, xy2, float(doc["camera"]["c"]) * k, approx, doc["sequence"]
    )


def dump(data: PairData, units: Units, columnar: bool) -> dict[str, Any]:
    """The kind's tables in the file's units."""
    k = units.mm_per_image
    cols = {
        "id": list(data.ids),
        "xl": json_numbers(data.xy_left[:, 0] / k),
        "yl": json_numbers(data.xy_left[:, 1] / k),
        "xr": json_numbers(data.xy_right[:, 0] / k),
        "yr": json_numbers(data.xy_right[:, 1] / k),
    }
    out: dict[str, Any] = {
        "camera": {"c": json_number(data.c / k)},
        "points": write_table(cols, columnar),
    }
    if data.approx:
        out["approx"] = {
            n: json_number(v / (units.m_per_length if n in LENGTHS else units.rad_per_angle))
            for n, v in data.approx.items()
        }
    return out


def solve(problem: Problem, method: str | None) -> Solution:
    """Relative orientation of the pair (rigorous, or via the essential matrix)."""
    data: PairData = problem.data
    opt = problem.options
    elements = opt.get("elements", "dependent")
    names = DEPENDENT if elements == "dependent" else INDEPENDENT
    L = problem.units.m_per_length
    base = opt.get("base", "median")
    if isinstance(base, str):  # the model at image scale: the x-parallax in mm read as length
        px = data.xy_left[:, 0] - data.xy_right[:, 0]
        b = float(np.mean(px) if base == "mean" else np.median(px)) * L
    else:
        b = float(base) * L
    sigma = float(opt.get("sigma", 0.005)) * L
    method = opt.get("method", "parallax")
    if method == "collinearity" and elements != "dependent":
        raise InputError(
            "method 'collinearity' gives a dependent pair; use elements 'dependent'",
            problem.source,
            "options.method",
        )
    approx = np.array([data.approx.get(n, 0.0) for n in names])
    route = opt.get("route", "rigorous")
    common = dict(b=b, sigma=sigma, sequence=data.sequence)
    if route == "essential":
        if elements != "dependent":
            raise InputError(
                "route 'essential' gives a dependent pair; use elements 'dependent'",
                problem.source,
                "options.route",
            )
        adj = essential_route(data.xy_left, data.xy_right, data.c, **common)
    else:
        adj = relative_orientation(
            data.xy_left, data.xy_right, data.c, kind=elements, approx=approx,
            max_iter=int(opt.get("max_iter", 20)), labels=list(data.ids), method=method,
            **common,
        )  # fmt: skip
    if getattr(adj, "method", "parallax") == "parallax":
        adj.obs_labels = [f"{i}/py" for i in data.ids]
    std = adj.std()
    params = [
        Parameter(n, float(adj.x[i]), float(std[i]), "length" if n in LENGTHS else "angle")
        for i, n in enumerate(names)
    ]
    params.insert(0, Parameter("bx", b, 0.0, "length"))
    used = getattr(adj, "method", "parallax")  # the essential route: parallax-like
    collinear = used == "collinearity"
    points = getattr(adj, "points", None)
    n = len(data.ids)
    if points is None or np.shape(points) != (n, 3):
        points = np.full((n, 3), np.nan)
    if collinear:  # the model points are unknowns: their σ (model units)
        point_sigma = std[5 : 5 + 3 * n].reshape(n, 3)
        observed = ("observations: the image coordinates of both images (collinearity "
                    "equations, model points unknown; residuals in units.image)")  # fmt: skip
        what = "model points (adjusted with the elements, ± σ)"
    else:
        point_sigma = np.full((n, 3), np.nan)
        observed = ("observations: rigorous y-parallaxes p_y = Y_left − Y_right in "
                    "units.length")  # fmt: skip
        if used == "coplanarity":
            observed = ("observations: one coplanarity condition per point, residual = the "
                        "triple product F = B·(r1 × r2) with r = R (x, y, −c)/c, in "
                        "units.length; its σ propagated from the image coordinates")  # fmt: skip
        what = "model points: the rays' meeting points in the XZ projection (no σ)"
    return Solution(
        kind="pair",
        method=f"{route} ({elements} pair, {used})",
        adjustment=adj,
        units=problem.units,
        sequence=data.sequence,
        parameters=params,
        point_ids=list(data.ids),
        xyz=np.asarray(points, float),
        xyz_sigma=point_sigma,
        point_roles=["model"] * n,
        observation_quantity="image" if collinear else "length",
        critical=float(opt.get("critical", W_CRITICAL)),
        notes=[
            "model frame: origin at the left projection centre, X along the base, Y left, "
            f"Z up, in units.length; {observed}",
            f"{what}; base bx = {'the ' + base + ' x-parallax' if isinstance(base, str) else 'given'}",
        ],
    )


KIND = register_kind(
    Kind(
        name="pair",
        schema="pair.json",
        load=load,
        dump=dump,
        solve=solve,
        description="relative orientation of a stereo pair from homologous image points",
        methods=("pair",),
    )
)
