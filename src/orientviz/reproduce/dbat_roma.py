"""DBAT's ROMA bundle: a close-range block without control, self-calibrating, beside DBAT's report.

``orientviz reproduce dbat-roma``. Data: DBAT's ``data/script/romabundledemo`` shipped in
``datasets/dbat/roma`` (60 images of its "Roma" project by a Canon EOS 5D Mark II, 5616 ×
3744 px on a 24 mm high sensor, c = 24.3581 mm in its camera file; 90 561 marked image points of
26 321 object points, σ = 1 px; no control points; DBAT's measurement file
``markpts.txt`` gzipped, its other files as they are). Adjusted as DBAT's script does:

* the backward lens model (DBAT "model 3") with c, px, py, K1, K2 free and the aspect,
  skew, K3, P1, P2 held at 0, starting from the camera file's values;
* the stations start at DBAT's prior EO (``initial_eo.txt``, degrees), the points at their
  forward intersection with that EO and the camera file's lens;
* the datum "dependent relative orientation": all six parameters of the first photo
  and one coordinate of another photo held at their start values. DBAT's report shows
  which: photo 19's Yc — the largest single base component (ΔY = 39.11 m) to the first
  photo; :func:`datum` derives that rule from the prior EO. orientviz holds them by
  pseudo-observations of σ = 1e-6 m / 1e-9 rad (``options.fix``,
  :mod:`orientviz.io.datum`) where DBAT removes them: the counts below are DBAT's
  (79 321 parameters), orientviz's n and u are each larger by those 7.

Published numbers: DBAT's report of this script (``roma/report.txt``), as printed.
"""

from __future__ import annotations

import copy
import gzip
from functools import lru_cache
from typing import Any

import numpy as np

from ..block import Block
from ..bundle import LensModel, bundle_adjust
from ..io.datasets import dataset_path
from ..io.datum import IMAGE_PARTS, apply_fix
from ..lens import BackwardLens, backward_ideal
from ..orientation.intersection import intersect_points
from ..rotation import matrix_from_opk
from . import Row
from .dbat_report import as_printed, predicted_rows, read_report, report_values, station_numbers

#: report key → name of the estimate in the camera result
IO_KEYS = {"c [mm]": "c", "px [mm]": "x0", "py [mm]": "y0", "K1 [mm^-3]": "K1", "K2 [mm^-5]": "K2",
           "as": "as", "K3 [mm^-7]": "K3", "P1 [mm^-3]": "P1", "P2 [mm^-3]": "P2"}  # fmt: skip
#: DBAT's script estimates these camera parameters (aspect, skew, K3, P1, P2 stay 0).
LENS_FREE = ("c", "x0", "y0", "K1", "K2")
#: The bundle's stopping rule (corrections below this fraction of their σ).
TOL = 1e-8


def _folder():
    return dataset_path("dbat_sxb").parent / "roma"


def _rows(path) -> list[list[str]]:
    """Comma-separated lines of a DBAT text file (``#`` comments skipped)."""
    opener = gzip.open if str(path).endswith(".gz") else open
    with opener(path, "rt", encoding="utf-8") as f:
        return [ln.split(",") for ln in f if ln.strip() and not ln.lstrip().startswith("#")]


def read_roma(folder=None) -> dict[str, Any]:
    """DBAT's ROMA files: images (id → file), prior EO (m, deg), marks (px), camera."""
    import xml.etree.ElementTree as ET

    folder = _folder() if folder is None else folder
    images = {r[0].strip(): r[1].strip().rsplit("/", 1)[-1] for r in _rows(folder / "images.txt")}
    eo = {r[0].strip(): [float(v) for v in r[1:7]] for r in _rows(folder / "initial_eo.txt")}
    marks = np.array([[float(v) for v in r[:4]] for r in _rows(folder / "markpts.txt.gz")])
    cam = ET.parse(folder / "EOS5DMarkII.xml").getroot().find("cameras/camera")
    width, height = (int(v) for v in cam.findtext("image").split(","))
    sensor_h = float(cam.findtext("sensor").split(",")[1])
    return {
        "images": images,
        "eo": eo,
        "marks": marks,  # image id, point id, column, row (px)
        "pixel_mm": sensor_h / height,  # "sensor auto,24": square pixels of 24 mm / 3744
        "image_px": (width, height),
        "c_mm": float(cam.findtext("cc")),
        "pp_mm": tuple(float(v) for v in cam.findtext("pp").split(",")),
        "K": tuple(float(v) for v in cam.findtext("K").split(",")),
    }


def datum(X0: np.ndarray) -> tuple[int, int]:
    """(photo, coordinate) held besides the first photo: the largest single component of
    the bases to the first photo (DBAT's ``ref_base="longest"``, as its report shows)."""
    d = np.abs(X0 - X0[0])
    k = int(np.argmax(d))
    return k // 3, k % 3


def block(folder=None):
    """The ROMA block (start values, datum held) as an orientviz :class:`~orientviz.block.Block`.

    Image coordinates in mm in the sensor frame (x = column · p, y = −row · p), the
    principal point at (px, −py), σ = 1 px; stations from the prior EO; points by
    forward intersection of the lens-corrected rays.
    """
    return _block(read_roma(folder))


def _block(d: dict[str, Any]):
    """:func:`block` from the files as :func:`read_roma` returns them."""
    p = d["pixel_mm"]
    ids = list(d["images"])
    m = d["marks"]
    order = {int(i): k for k, i in enumerate(ids)}
    im = np.array([order[int(v)] for v in m[:, 0]])
    pid, pt = np.unique(m[:, 1].astype(np.int64), return_inverse=True)
    xy = np.column_stack([m[:, 2] * p, -m[:, 3] * p])
    eo = np.array([d["eo"][i] for i in ids])
    X0, ang = eo[:, :3], np.radians(eo[:, 3:])
    c, (px, py), K = d["c_mm"], d["pp_mm"], d["K"]
    ideal = backward_ideal(xy, BackwardLens(c, px, -py, K=tuple(K)))
    R = matrix_from_opk(ang[:, 0], ang[:, 1], ang[:, 2])
    xyz = intersect_points(ideal, im, pt, X0, R, c, n_points=pid.size).xyz
    w, h = d["image_px"]
    blk = Block.from_arrays(
        camera_c=[c], camera_x0=[px], camera_y0=[-py], camera_format_mm=(w * p, h * p),
        camera_ids=["EOS5DMarkII"], image_camera=np.zeros(len(ids), np.int64), X0=X0,
        angles=ang, xyz=xyz, obs_image=im, obs_point=pt, obs_xy=xy, obs_sigma=p,
        image_ids=ids, point_ids=[str(q) for q in pid], meta={"name": "dbat-roma"},
    )  # fmt: skip
    k, comp = datum(X0)
    return apply_fix(blk, [(ids[0], ()), (ids[k], (IMAGE_PARTS[comp],))])


@lru_cache(maxsize=1)
def adjust():
    """Run DBAT's ROMA bundle through :func:`orientviz.bundle.bundle_adjust` with the
    backward :class:`~orientviz.bundle.LensModel` (c, x0, y0, K1, K2 free).

    Returns
    -------
    (BundleResult, image ids, DBAT data)
    """
    d = read_roma()
    lens = LensModel("backward", free=LENS_FREE, values={"K1": d["K"][0], "K2": d["K"][1]})
    res = bundle_adjust(_block(d), additional=lens, tol=TOL, max_iter=50)
    return res, list(d["images"]), d


def paper_values() -> dict[str, str | float]:
    """DBAT's published numbers (its report of the script), strings as printed."""
    return copy.deepcopy(_published()[0])


@lru_cache(maxsize=1)
def _published():
    return as_printed(report_values(read_report(_folder() / "report.txt")))


def ours() -> dict[str, float]:
    """orientviz's numbers under the report's keys (unrounded)."""
    res, ids, d = adjust()
    held = 7  # the datum's pseudo-observations (DBAT removes those parameters instead)
    out: dict[str, float] = {
        "summary||sigma0": res.sigma0,
        "summary||sigma0 [px]": res.sigma0 * 1.0,  # σ of the marks is 1 px
        "summary||redundancy": float(res.redundancy),
        "summary||parameters": float(res.adjusted[1] - held),
        "summary||observations": float(res.adjusted[0] - held),
        "summary||sqrt(vTPv)": res.sigma0 * np.sqrt(res.redundancy),
    }
    cam = res.camera
    sign = {"y0": -1.0}  # DBAT prints py downwards
    for key, name in IO_KEYS.items():
        j = cam.names.index(name)
        out[f"camera||{key}"] = float(cam.value[0, j] * sign.get(name, 1.0))
        if name in LENS_FREE:  # the others are held at 0 (no σ, as in DBAT's report)
            out[f"camera||σ {key}"] = float(cam.sigma[0, j])
    n = res.used_obs.size
    v = res.residuals[: 2 * n].reshape(n, 2) / d["pixel_mm"]
    out["residuals||overall point RMS [px]"] = float(np.sqrt(np.mean(np.sum(v**2, axis=1))))
    eo = res.exterior
    Q = res.cofactor_groups["exterior"]
    for i, ident in enumerate(ids):
        vals = np.r_[np.degrees(eo[i, 3:]), eo[i, :3]]
        s = res.sigma0 * np.sqrt(np.diag(Q[i]))
        sig = np.r_[np.degrees(s[3:]), s[:3]]
        station_numbers(out, f"photo {i + 1} ({d['images'][ident]})", vals, sig, Q[i])
    return out


def table(*, paper: dict[str, Any] | None = None) -> list[Row]:
    """One row per published number of DBAT's ROMA report, orientviz's beside it."""
    paper = paper_values() if paper is None else paper
    return predicted_rows(paper, ours(), _published()[1])
