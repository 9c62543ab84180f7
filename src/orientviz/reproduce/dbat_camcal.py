"""DBAT's camera calibration demo: orientviz's self-calibrating bundle beside DBAT's report.

``orientviz reproduce dbat-camcal``. Data: DBAT's ``data/script/camcaldemo`` shipped in
``datasets/dbat/camcal`` (21 images of a target sheet by an Olympus C4040Z, 2272 × 1704
px, sensor height 5.43764 mm with square pixels, nominal focal length 7.5 mm; 2074
marked points with σ = 0.1 px; 4 control points held fixed). Adjusted as DBAT's script
does: the backward lens model (DBAT "model 3") with c, px, py, aspect, K1-K3, P1, P2
free and the skew fixed at 0; all 21 stations and the 96 other points free; no prior
observations. Start: c = 7.5 mm, principal point at the sensor centre, no distortion;
stations by space resection on the four control points
(:func:`orientviz.orientation.resection.resection_closed_form`), points by forward
intersection — DBAT's script does the same two operations. The adjustment is the
ordinary bundle (:func:`orientviz.bundle.bundle_adjust`, points eliminated, the camera
parameters bordering the reduced system) with the camera model inside the projection
(:class:`orientviz.bundle.LensModel`, ``kind="backward"``).

Published numbers: DBAT's report of the same data through its PhotoModeler-export route
(``camcal-dbatreport.txt``), as printed; the report of
the script route (``report.txt``) differs from it in a few last digits (two DBAT runs of
the same adjustment stopped at slightly different iterates), which bounds what "the
printed digit" can mean here.
"""

from __future__ import annotations

import copy
from functools import lru_cache
from typing import Any

import numpy as np

from ..block import Block
from ..bundle import LensModel, bundle_adjust
from ..io.datasets import dataset_path
from ..io.problem import dumps_problem, loads_problem
from ..lens import BackwardLens, backward_ideal
from ..orientation.intersection import intersect_points
from ..orientation.resection import resection_closed_form
from ..rotation import matrix_from_opk
from . import Row
from .dbat_files import read_camcal
from .dbat_report import EO_FIELDS, as_printed, read_report, report_values

IO_NAMES = ("c", "px", "py", "as", "K1", "K2", "K3", "P1", "P2")
#: report key → position in the interior-orientation vector
IO_KEYS = {"c [mm]": 0, "px [mm]": 1, "py [mm]": 2, "as": 3, "K1 [mm^-3]": 4, "K2 [mm^-5]": 5,
           "K3 [mm^-7]": 6, "P1 [mm^-3]": 7, "P2 [mm^-3]": 8}  # fmt: skip
#: The stations' acceptance: within this fraction of DBAT's σ of DBAT's values.
STATION_SIGMA_FRACTION = 0.05


def _folder():
    return dataset_path("dbat_sxb").parent / "camcal"


def paper_values() -> dict[str, str | float]:
    """DBAT's published numbers (PhotoModeler-export route), strings as printed."""
    return copy.deepcopy(_published())


@lru_cache(maxsize=1)
def _published() -> dict[str, str | float]:
    return as_printed(report_values(read_report(_folder() / "camcal-dbatreport.txt")))[0]


@lru_cache(maxsize=1)
def _decimals() -> dict[str, int]:
    """Decimals of the numbers DBAT printed in exponent notation (from its report)."""
    return as_printed(report_values(read_report(_folder() / "camcal-dbatreport.txt")))[1]


def _setup(folder=None):
    """Observations (measured mm in the sensor frame), indices, control and start values."""
    d = read_camcal(_folder() if folder is None else folder)
    p = d["pixel_mm"]
    img_ids = list(d["images"])
    ctrl = d["control"]
    pts = sorted({m[1] for m in d["marks"]} - set(ctrl), key=int)
    im = np.array([img_ids.index(m[0]) for m in d["marks"]])
    pid = [m[1] for m in d["marks"]]
    is_ctrl = np.array([q in ctrl for q in pid])
    free = {q: k for k, q in enumerate(pts)}
    pt = np.array([free.get(q, -1) for q in pid])
    ctrl_xyz = np.array([ctrl.get(q, (np.nan,) * 3) for q in pid])
    measured = np.column_stack([[m[2] * p for m in d["marks"]], [-m[3] * p for m in d["marks"]]])
    sigma = np.repeat([m[4] * p for m in d["marks"]], 2)
    return d, img_ids, pts, im, pt, is_ctrl, ctrl_xyz, measured, sigma


def _start(d, img_ids, pts, im, pt, is_ctrl, ctrl_xyz, measured):
    """Start values: nominal interior orientation, resection on control, intersection."""
    w, h = d["sensor_mm"]
    io = np.array([d["focal_mm"], w / 2, h / 2, 0, 0, 0, 0, 0, 0], dtype=float)
    ideal = backward_ideal(measured, BackwardLens(io[0], io[1], -io[2]))
    m = len(img_ids)
    eo = np.zeros((m, 6))
    for i in range(m):
        sel = (im == i) & is_ctrl
        cand = resection_closed_form(ideal[sel], ctrl_xyz[sel], float(io[0]))[0]
        eo[i, :3] = cand.X0
        eo[i, 3:] = cand.angles("opk")
    free = pt >= 0
    R = matrix_from_opk(eo[:, 3], eo[:, 4], eo[:, 5])
    res = intersect_points(ideal[free], im[free], pt[free], eo[:, :3], R, float(io[0]),
                           n_points=len(pts))  # fmt: skip
    return io, eo, res.xyz


def block(folder=None):
    """DBAT's calibration data as an orientviz :class:`~orientviz.block.Block` (start values).

    One camera (c = 7.5 mm, principal point at the sensor centre, in the sensor frame:
    x right, y up from the upper-left corner, mm), the 21 stations from the resections,
    the 96 free points from the intersection and the 4 control points (fixed).
    """
    d, img_ids, pts, im, pt, is_ctrl, ctrl_xyz, measured, sigma = _setup(folder)
    io, eo, xyz = _start(d, img_ids, pts, im, pt, is_ctrl, ctrl_xyz, measured)
    ctrl = sorted(d["control"], key=int)
    ids = list(pts) + ctrl
    where = {q: i for i, q in enumerate(ids)}
    w, h = d["sensor_mm"]
    return Block.from_arrays(
        camera_c=[io[0]], camera_x0=[w / 2], camera_y0=[-h / 2], camera_format_mm=(w, h),
        camera_ids=["C4040Z"], image_camera=np.zeros(len(img_ids), np.int64), X0=eo[:, :3],
        angles=eo[:, 3:], xyz=np.vstack([xyz, [d["control"][q] for q in ctrl]]),
        obs_image=im, obs_point=[where[m[1]] for m in d["marks"]], obs_xy=measured,
        obs_sigma=sigma.reshape(-1, 2), role=[0] * len(pts) + [1] * len(ctrl),
        image_ids=img_ids, point_ids=ids, meta={"name": "dbat-camcal"},
    )  # fmt: skip


def problem_document(folder=None) -> dict:
    """The calibration as an orientviz problem file (kind block, image units px).

    DBAT's pixel measurements as they are (origin at the upper-left corner, y down,
    σ 0.1 px), the camera with ``"model": "backward"`` and DBAT's free parameters, the
    start orientations of :func:`block` (tie points without coordinates: the loader
    intersects them).
    """
    blk = block(folder)
    d = _setup(folder)[0]
    p = d["pixel_mm"]
    w, h = d["sensor_mm"]
    im, pt, ob = blk.images, blk.points, blk.observations
    ctrl = pt.role == 1
    return {
        "format": "orientviz/1", "kind": "block", "name": "dbat-camcal",
        "description": "DBAT's camera calibration demo (Börlin & Grussenmeyer; BSD licence, see datasets/dbat)",
        "units": {"length": "m", "angle": "rad", "image": "px", "pixel_size": p},
        "sequence": "opk",
        "cameras": [{"id": "C4040Z", "c": d["focal_mm"] / p, "x0": w / 2 / p, "y0": h / 2 / p,
                     "format": [w / p, h / p], "model": "backward", "free": list(LENS_FREE)}],
        "images": {"id": list(im.ids), "camera": ["C4040Z"] * len(im.ids),
                   "X0": im.X0[:, 0].tolist(), "Y0": im.X0[:, 1].tolist(), "Z0": im.X0[:, 2].tolist(),
                   "omega": im.angles[:, 0].tolist(), "phi": im.angles[:, 1].tolist(),
                   "kappa": im.angles[:, 2].tolist()},
        "points": {"id": list(pt.ids), "role": ["control" if c else "tie" for c in ctrl],
                   "X": [float(v) if c else None for v, c in zip(pt.xyz_known[:, 0], ctrl)],
                   "Y": [float(v) if c else None for v, c in zip(pt.xyz_known[:, 1], ctrl)],
                   "Z": [float(v) if c else None for v, c in zip(pt.xyz_known[:, 2], ctrl)]},
        "observations": {"image": [im.ids[i] for i in ob.image], "point": [pt.ids[j] for j in ob.point],
                         "x": (ob.xy[:, 0] / p).tolist(), "y": (-ob.xy[:, 1] / p).tolist(),
                         "sigma": (ob.sigma[:, 0] / p).tolist()},
        "options": {"tol": TOL, "max_iter": 50},
    }  # fmt: skip


def problem_text(folder=None) -> str:
    """:func:`problem_document` through orientviz's reader and writer (validated,
    canonical form): the text of the shipped dataset ``dbat_camcal``."""
    import json

    return dumps_problem(loads_problem(json.dumps(problem_document(folder)), "dbat_camcal.json"))


#: The dataset's entry in datasets/dbat/MANIFEST.json (written by make_dbat).
MANIFEST_ENTRY = {
    "name": "dbat_camcal",
    "file": "dbat_camcal.json",
    "kind": "block",
    "form": "columnar",
    "description": "DBAT's camera calibration demo: 21 images of a target sheet by an Olympus C4040Z (2272 x 1704 px of 3.19 um), 2074 marked points (sigma 0.1 px), 4 fixed control points; the camera estimated with DBAT's backward lens model (c, principal point, aspect, K1-K3, P1, P2)",
    "source": "DBAT 0.9.2.0 (https://github.com/niclasborlin/dbat), data/script/camcaldemo (copies in camcal/); made by orientviz.reproduce.dbat_camcal.write_problem from those copies (start orientations by resection on the control points)",
    "citation": "CITATION.md",
    "licence": "BSD-style licence of DBAT, (C) 2013-2020 N. Börlin and P. Grussenmeyer: LICENSE.txt",
    "units": {"length": "m", "image": "px", "angle": "rad"},
    "frame": "object: DBAT's target-sheet frame (m); image: pixels from the upper-left corner, y down (units.image px, pixel_size 0.0031911 mm)",
    "adjustment": "as DBAT's camcal demo: all stations and points free, 4 control points fixed, camera model backward with c, x0, y0, as, K1-K3, P1, P2 free and sk fixed at 0; orientviz reproduce dbat-camcal compares every printed number",
}


#: DBAT's demo estimates every parameter of its model 3 but the shear (no priors).
LENS_FREE = ("c", "x0", "y0", "as", "K1", "K2", "K3", "P1", "P2")


@lru_cache(maxsize=1)
def adjust():
    """Run the calibration through :func:`orientviz.bundle.bundle_adjust` with the
    backward :class:`~orientviz.bundle.LensModel`.

    Returns
    -------
    (BundleResult, image ids, point ids, DBAT data)
        ``result.camera`` holds c, x0, y0 (y up: DBAT's py = −y0), as, K1-K3, P1, P2.
    """
    d, img_ids, pts = _setup()[:3]
    res = bundle_adjust(block(), additional=LensModel("backward", free=LENS_FREE), tol=TOL,
                        max_iter=50)  # fmt: skip
    return res, img_ids, pts, d


#: The bundle's stopping rule: corrections below this fraction of their conditional σ
#: (DBAT iterates to its own tolerance; the printed digits need the optimum closely).
TOL = 1e-8


def camera_values(res) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(values (9,), σ (9,), correlations (9, 9)) in DBAT's order and signs (IO_NAMES)."""
    cam = res.camera
    j = [cam.names.index(k) for k in LENS_FREE]
    sign = np.ones(9)
    sign[2] = -1.0  # DBAT prints py downwards
    rho = cam.correlation[0][np.ix_(j, j)] * np.outer(sign, sign)
    return cam.value[0, j] * sign, cam.sigma[0, j], rho


def ours() -> dict[str, float]:
    """orientviz's numbers under the report's keys (unrounded)."""
    res, img_ids, pts, d = adjust()
    out: dict[str, float] = {
        "summary||sigma0": res.sigma0,
        "summary||sigma0 [px]": res.sigma0 * 0.1,
        "summary||redundancy": float(res.redundancy),
        # unknowns: stations, free points, camera (``res.x`` also lists the fixed control)
        "summary||parameters": float(6 * len(img_ids) + 3 * len(pts) + res.additional.size),
        "summary||observations": float(res.n_observations),
        "summary||sqrt(vTPv)": res.sigma0 * np.sqrt(res.redundancy),
    }
    value, sigma, rho = camera_values(res)
    for key, k in IO_KEYS.items():
        out[f"camera||{key}"] = float(value[k])
        out[f"camera||σ {key}"] = float(sigma[k])
    short = [k.split()[0] for k in IO_KEYS]
    for a in range(9):
        for b in range(a + 1, 9):
            out[f"camera||correlation {short[a]}-{short[b]} [%]"] = 100.0 * float(rho[a, b])
    n = res.used_obs.size
    v = res.residuals[: 2 * n].reshape(n, 2) / d["pixel_mm"]
    out["residuals||overall point RMS [px]"] = float(np.sqrt(np.mean(np.sum(v**2, axis=1))))
    eo = res.exterior
    seo = res.sigma0 * np.sqrt(np.einsum("mii->mi", res.cofactor_groups["exterior"]))
    for i, num in enumerate(img_ids):
        case = f"photo {int(num)} ({d['images'][num]})"
        vals = np.r_[np.degrees(eo[i, 3:]), eo[i, :3]]
        sig = np.r_[np.degrees(seo[i, 3:]), seo[i, :3]]
        for j, (_, name) in enumerate(EO_FIELDS):
            out[f"stations|{case}|{name}"] = float(vals[j])
            out[f"stations|{case}|σ {name}"] = float(sig[j])
    return out


@lru_cache(maxsize=1)
def _script_route() -> dict[str, str]:
    """DBAT's report of the same adjustment through its script route (``report.txt``)."""
    return report_values(read_report(_folder() / "report.txt"))


def _note(key: str, value: float | None) -> str:
    if value is None:
        return "not computed by orientviz"
    other = _script_route().get(key)
    mine = report_values(read_report(_folder() / "camcal-dbatreport.txt")).get(key)
    if other is not None and mine is not None and other != mine:
        return f"DBAT's script route prints {other} (two DBAT runs differ in this digit)"
    return ""


def table(*, paper: dict[str, Any] | None = None) -> list[Row]:
    """One row per published number of DBAT's calibration report, orientviz's beside it."""
    paper = paper_values() if paper is None else paper
    mine = ours()
    rows = []
    for key, printed in paper.items():
        section, case, quantity = key.split("|")
        value = mine.get(key)
        rows.append(Row(section, case, quantity, printed,
                        None if value is None else f"{value:.7g}", note=_note(key, value),
                        label="predicted", value=value, key=key, group=section,
                        decimals=_decimals().get(key) if isinstance(printed, float) else None))  # fmt: skip
    return rows
