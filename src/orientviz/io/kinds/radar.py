"""Kind ``radar``: orientation of radar panorama (PPI) images (Geier 1973).

The file names a ``task`` and gives:

* ``points`` — object points ``id, X, Y, Z`` (control; a relative orientation needs none),
* ``images`` — per image ``id``, interior ``x0, y0, h, m`` and exterior ``X0 [X, Y, Z],
  phi, omega, kappa``: known values and approximations of the unknowns,
* ``observations`` — ``image, point, x, y`` and an optional ``sigma``.

Radar image coordinates, x0, y0, h and X0 are lengths in ``units.length`` (the paper
uses metres; ``units.image`` does not apply), the scale m is a pure number, angles are in
``units.angle`` and the file's ``sequence`` (the paper's is ``pok``: R = R_φ R_ω R_κ,
κ being the reference direction α0). Tasks (:mod:`orientviz.radar.orientation`,
:mod:`orientviz.radar.pair`):

``calibration`` (x0, y0, h, m, κ of one image), ``trilateration`` (X0 from the ranges),
``rotations`` (φ, ω, κ), ``exterior`` (six), ``all`` (ten), ``relative`` (the second of
two images against the first, fixed; ``options.free`` may add its interior orientation).
``options.stopping`` = ``"geier"`` uses the stopping rule reconstructed from Geier's Fig. 8.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...adjust.result import W_CRITICAL
from ...errors import InputError
from ...radar import geier1973 as G
from ...radar import orientation as O
from ...radar.pair import relative_orientation
from ...radar.ppi import EXTERIOR, PARAMS, RadarImage
from ...units import from_rad
from ..problem import Problem, Units
from ..registry import Kind, register_kind
from ..solution import Parameter, Solution
from ..tables import REQUIRED, json_number, json_numbers, read_table, write_table

F64 = NDArray[np.float64]
TASKS = ("calibration", "trilateration", "rotations", "exterior", "all", "relative")
POINT_FIELDS = {"id": REQUIRED, "X": REQUIRED, "Y": REQUIRED, "Z": REQUIRED}
OBS_FIELDS = {"image": REQUIRED, "point": REQUIRED, "x": REQUIRED, "y": REQUIRED, "sigma": None}
LENGTH_KEYS = ("x0", "y0", "h")
ANGLE_KEYS = ("phi", "omega", "kappa")


@dataclass
class RadarData:
    """A radar problem in internal units (m, rad)."""

    task: str
    point_ids: list[str]
    points: F64
    image_ids: list[str]
    images: list[Any]  # RadarImage
    obs_image: NDArray[np.int64]
    obs_point: NDArray[np.int64]
    xy: F64
    sigma: F64
    sequence: str = "pok"
    meta: dict[str, Any] = field(default_factory=dict)


def load(doc: dict[str, Any], units: Units, source: str) -> RadarData:
    """Read a ``radar`` document into :class:`RadarData` (m, rad)."""
    L, A = units.m_per_length, units.rad_per_angle
    seq = doc.get("sequence", "pok")
    task = doc["task"]
    pt = read_table(doc, "points", POINT_FIELDS, source, optional=task == "relative")
    pids = pt.index("id", "point")
    P = np.column_stack([pt.floats("X", L), pt.floats("Y", L), pt.floats("Z", L)]).reshape(-1, 3)
    images, iids = [], {}
    for k, node in enumerate(doc["images"]):
        where = f"images[{k}]"
        ident = str(node["id"])
        if ident in iids:
            raise InputError(f"duplicate image id {ident!r}", source, f"{where}.id")
        iids[ident] = k
        try:
            images.append(
                RadarImage(
                    float(node["x0"]) * L,
                    float(node["y0"]) * L,
                    float(node["h"]) * L,
                    float(node["m"]),
                    tuple(float(v) * L for v in node["X0"]),
                    float(node.get("phi", 0.0)) * A,
                    float(node.get("omega", 0.0)) * A,
                    float(node.get("kappa", 0.0)) * A,
                    sequence=seq,
                )  # fmt: skip
            )
        except InputError as exc:
            raise InputError(exc.message, source, where) from None
    ot = read_table(doc, "observations", OBS_FIELDS, source)
    oi = ot.lookup("image", iids, "image")
    op = ot.lookup("point", pids, "point") if task != "relative" else None
    if task == "relative":
        # points need not be listed: homologous points are matched by their names
        names = ot.strings("point")
        order = list(dict.fromkeys(names))
        op = np.array([order.index(n) for n in names], dtype=np.int64)
        if not pt.n:
            P = np.full((len(order), 3), np.nan)
            pids = {n: i for i, n in enumerate(order)}
    xy = np.column_stack([ot.floats("x", L), ot.floats("y", L)])
    sig = ot.floats("sigma", L)
    sig = np.where(np.isnan(sig), L, sig)
    if np.any(sig <= 0):
        raise ot.fail(int(np.flatnonzero(sig <= 0)[0]), "sigma", "expected σ > 0")
    n_img = 2 if task == "relative" else 1
    if len(images) != n_img:
        raise InputError(
            f"task {task!r} needs {n_img} image(s), got {len(images)}", source, "images"
        )
    return RadarData(
        task, list(pids), P, list(iids), images, oi, op, xy, sig, seq,
        {"free": (doc.get("options") or {}).get("free")},
    )  # fmt: skip


def dump(data: RadarData, units: Units, columnar: bool) -> dict[str, Any]:
    L, A = units.m_per_length, units.rad_per_angle
    out: dict[str, Any] = {"task": data.task}
    if np.any(np.isfinite(data.points)):
        out["points"] = write_table(
            {
                "id": list(data.point_ids),
                "X": json_numbers(data.points[:, 0] / L),
                "Y": json_numbers(data.points[:, 1] / L),
                "Z": json_numbers(data.points[:, 2] / L),
            },
            columnar,
        )
    imgs = []
    for ident, im in zip(data.image_ids, data.images):
        node = {"id": ident}
        node.update({k: json_number(getattr(im, k) / L) for k in LENGTH_KEYS})
        node["m"] = json_number(im.m)
        node["X0"] = json_numbers(np.asarray(im.X0) / L)
        node.update({k: json_number(getattr(im, k) / A) for k in ANGLE_KEYS})
        imgs.append(node)
    out["images"] = imgs
    sig = [None if abs(s - L) < 1e-15 * L else json_number(s / L) for s in data.sigma]
    out["observations"] = write_table(
        {
            "image": [data.image_ids[i] for i in data.obs_image],
            "point": [data.point_ids[i] for i in data.obs_point],
            "x": json_numbers(data.xy[:, 0] / L),
            "y": json_numbers(data.xy[:, 1] / L),
            "sigma": sig,
        },
        columnar,
    )
    return out


def _observed(data: RadarData, image: int) -> tuple[F64, F64, NDArray[np.int64]]:
    sel = np.flatnonzero(data.obs_image == image)
    idx = data.obs_point[sel]
    return data.xy[sel], data.sigma[sel], idx


def solve(problem: Problem, method: str | None) -> Solution:
    """Run the file's task and report the image(s) and the interior parameters."""
    data: RadarData = problem.data
    opts = dict(problem.options or {})
    stopping = opts.get("stopping", "converge")
    engine = {k: opts[k] for k in ("max_iter", "tol") if k in opts}
    if data.task == "relative":
        xy1, s1, i1 = _observed(data, 0)
        xy2, s2, i2 = _observed(data, 1)
        common = np.intersect1d(i1, i2)
        if common.size == 0:
            raise InputError(
                "the two images have no point in common", problem.source, "observations"
            )
        a = {p: k for k, p in enumerate(i1)}
        b = {p: k for k, p in enumerate(i2)}
        ka, kb = [a[p] for p in common], [b[p] for p in common]
        free = data.meta.get("free") or list(EXTERIOR)
        res = relative_orientation(
            xy1[ka], data.images[0], xy2[kb], data.images[1], free=free, damping="lm", **engine
        )
        img_k, pts = 1, res.points
        point_ids = [data.point_ids[p] for p in common]
    else:
        xy, s, idx = _observed(data, 0)
        P = data.points[idx]
        if not np.all(np.isfinite(P)):
            raise InputError("observed points need X, Y, Z for this task", problem.source, "points")
        start = data.images[0]
        kw = dict(sigma=s, labels=[data.point_ids[i] for i in idx], **engine)
        if data.task == "trilateration":
            res = O.station_by_trilateration(P, xy, start, **kw)
        else:
            fn = {"calibration": O.calibrate, "rotations": O.rotations, "exterior": O.exterior,
                  "all": O.resect_all}[data.task]  # fmt: skip
            res = fn(P, xy, start, stopping=stopping, **kw)
        img_k, pts, point_ids = 0, np.zeros((0, 3)), []
    est = res.image
    std = dict(zip(res.names, res.std()))
    sd = {n: std.get(n, 0.0) for n in PARAMS}
    params = [
        Parameter(n, float(getattr(est, n)), float(sd[n]), "length" if n != "m" else "1")
        for n in ("x0", "y0", "h", "m")
    ]
    X0 = np.asarray(est.X0, float)[None, :]
    angles = np.array([[est.omega, est.phi, est.kappa]])
    ps = res.std()
    n_img_par = len(res.names) - 3 * len(point_ids)
    xyz_sigma = ps[n_img_par:].reshape(-1, 3) if point_ids else np.zeros((0, 3))
    return Solution(
        kind="radar",
        method=data.task,
        adjustment=res,
        units=problem.units,
        sequence=data.sequence,
        image_ids=[data.image_ids[img_k]],
        X0=X0,
        angles=angles,
        X0_sigma=np.array([[sd["X0"], sd["Y0"], sd["Z0"]]]),
        angles_sigma=np.array([[sd["omega"], sd["phi"], sd["kappa"]]]),
        point_ids=point_ids,
        xyz=pts,
        xyz_sigma=xyz_sigma,
        point_roles=["tie"] * len(point_ids),
        parameters=params,
        observation_quantity="length",
        critical=float(opts.get("critical", W_CRITICAL)),
        notes=[
            f"radar task {data.task!r} ({res.task}); unknowns: " + ", ".join(res.names[:n_img_par]),
            "image coordinates and residuals in units.length; kappa is the reference "
            "direction alpha0; sequence " + data.sequence,
        ],
    )


def radar_problem_from_geier(surface: str = "fig7", task: str = "calibration") -> dict[str, Any]:
    """A problem document (dict, m and gon) for a Geier 1973 test image.

    ``task`` ``"calibration"``/``"exterior"``/``"trilateration"``/``"rotations"`` use image
    2 with the Fig. 7 approximations, ``"all"`` image 3, ``"relative"`` images 1 and 2.
    """
    if task not in TASKS:
        raise InputError(f"unknown radar task {task!r}; expected one of {', '.join(TASKS)}")
    T, A = G.images(), G.approximations()
    img = 3 if task == "all" else 2
    a = A[img]
    start = {
        "calibration": T[2].with_(x0=a.x0, y0=a.y0, h=a.h, m=a.m, kappa=G.alpha0_approx()),
        "trilateration": T[2].with_(X0=a.X0),
        "rotations": T[2].with_(phi=0.0, omega=0.0, kappa=0.0),
        "exterior": T[2].with_(X0=a.X0, phi=0.0, omega=0.0, kappa=0.0),
        "all": a,
        "relative": T[2].with_(X0=a.X0, phi=0.0, omega=0.0, kappa=0.0),
    }[task]
    ims = [(str(img), start)] if task != "relative" else [("1", T[1]), ("2", start)]

    def node(ident, im):
        return {
            "id": ident, "x0": im.x0, "y0": im.y0, "h": im.h, "m": im.m, "X0": list(im.X0),
            **{k: float(np.round(from_rad(getattr(im, k), "gon"), 10)) for k in ANGLE_KEYS},
        }  # fmt: skip

    P = G.points(surface)
    obs = []
    for ident, _ in ims:
        xy = G.image_coordinates(surface, int(ident))
        obs += [{"image": ident, "point": str(i + 1), "x": float(x), "y": float(y)}
                for i, (x, y) in enumerate(xy)]  # fmt: skip
    doc = {
        "format": "orientviz/1",
        "kind": "radar",
        "name": f"Geier 1973, {surface}, {task}",
        "description": "radar panorama image of Geier (1973) Fig. 7; image coordinates rounded to whole metres",
        "units": {"length": "m", "angle": "gon"},
        "sequence": "pok",
        "task": task,
        "images": [node(i, im) for i, im in ims],
        "observations": obs,
    }
    if task != "relative":
        doc["points"] = [
            {"id": str(i + 1), "X": float(p[0]), "Y": float(p[1]), "Z": float(np.round(p[2], 6))}
            for i, p in enumerate(P)
        ]
    return doc


KIND = register_kind(
    Kind(
        name="radar",
        schema="radar.json",
        load=load,
        dump=dump,
        solve=solve,
        description="radar panorama (PPI) images: calibration, exterior, all ten, relative",
        methods=TASKS,
    )
)
