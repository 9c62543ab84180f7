"""Image measurements from a CSV table: ``orientviz import-csv``.

The path for data that comes neither from COLMAP nor BAL — a PhotoModeler or DBAT table
of marked points, a spreadsheet, a digitiser: one row per image point ::

    image,point,x,y,sigma
    8811,317,5007.6667,7275.6667,0.5
    8811,333,2158.25,1135.5,0.5
    8936,317,1453.6667,1012.3333,

``image`` and ``point`` are ids (any text), ``x, y`` the measured image coordinates,
``sigma`` (optional, empty = ``--sigma``) their a-priori σ in the same unit.

* ``--units px`` (default): pixels from the upper-left corner of the image, x to the
  right, y *down* (rows), as image viewers, PhotoModeler and DBAT write them; converted
  with ``--pixel-size`` p (mm) to orientviz's frame x = x_px · p, y = −y_px · p (mm).
  The principal point ``--principal-point PX PY`` is then given in mm from the same
  corner, PY down (as PhotoModeler and DBAT print it): x0 = PX, y0 = −PY.
* ``--units mm``: coordinates already in orientviz's image frame (mm, x right, y up),
  the principal point (x0, y0) in that frame.

The camera is ``--c`` (principal distance, mm) with ``--format W H`` (mm; default the
extent of the measurements). Control points come from ``--control`` (the control CSV
of :mod:`orientviz.io.control`, keyed by the point ids). The images get no approximate
orientation: ``orientviz solve`` computes them (relative orientation of a seed pair,
resections, intersections, a similarity onto the control). Every broken line raises
one :class:`~orientviz.errors.InputError` naming file and line.
"""

from __future__ import annotations

import argparse
import os
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..block import Block
from ..errors import InputError
from .control import _num, csv_table
from .importing import import_to_problem

F64 = NDArray[np.float64]
REQUIRED = ("image", "point", "x", "y")
#: Image coordinates beyond ± this (px or mm) are refused.
MAX_COORDINATE: float = 1e7


@dataclass
class Measurements:
    """Rows of a measurement CSV: ids, ``xy`` and ``sigma`` (n,) in the file's unit, lines."""

    image: list[str]
    point: list[str]
    xy: F64
    sigma: F64  # NaN = not given
    lines: list[int]
    source: str


def read_measurements(path: str | os.PathLike[str]) -> Measurements:
    """Read a measurement CSV (header ``image,point,x,y[,sigma]``), checked line by line."""
    source = str(path)
    rows, head, col = csv_table(path, "a measurement CSV file", REQUIRED, "empty file", "[,sigma]")
    img, pt, xy, sig, lines = [], [], [], [], []
    seen: dict[tuple[str, str], int] = {}
    for no, r in enumerate(rows[1:], start=2):
        if not any(c.strip() for c in r):
            continue
        if len(r) != len(head):
            raise InputError(f"expected {len(head)} cells, got {len(r)}", source, f"line {no}")
        i, p = r[col["image"]].strip(), r[col["point"]].strip()
        if not i or not p:
            raise InputError("empty image or point id", source, f"line {no}")
        if max(len(i), len(p)) > 256:
            raise InputError("an id of more than 256 characters", source, f"line {no}")
        if (i, p) in seen:
            raise InputError(f"point {p!r} measured twice in image {i!r} (also line "
                             f"{seen[(i, p)]})", source, f"line {no}")  # fmt: skip
        seen[(i, p)] = no
        x = _num(r[col["x"]], "x", source, no, np.nan)
        y = _num(r[col["y"]], "y", source, no, np.nan)
        if not (np.isfinite(x) and np.isfinite(y)):
            raise InputError("x and y are required", source, f"line {no}")
        if max(abs(x), abs(y)) > MAX_COORDINATE:
            raise InputError(f"x, y beyond ±{MAX_COORDINATE:g} (px or mm): not an image "
                             "position", source, f"line {no}")  # fmt: skip
        s = _num(r[col["sigma"]], "sigma", source, no, np.nan) if "sigma" in col else np.nan
        if s <= 0:
            raise InputError(f"sigma: expected > 0, got {s:g}", source, f"line {no}")
        img.append(i)
        pt.append(p)
        xy.append((x, y))
        sig.append(s)
        lines.append(no)
    if not img:
        raise InputError("no measurements in the file", source, f"line {len(rows)}")
    return Measurements(img, pt, np.array(xy, float), np.array(sig, float), lines, source)


def block_from_measurements(
    m: Measurements,
    *,
    c: float,
    units: str = "px",
    pixel_size_mm: float | None = None,
    principal_point: tuple[float, float] = (0.0, 0.0),
    format_mm: tuple[float, float] | None = None,
    sigma: float = 1.0,
) -> Block:
    """A block of one camera from measurements (see the module docstring for the frames).

    Parameters
    ----------
    m : Measurements
    c : float
        Principal distance (mm).
    units : {"px", "mm"}
        Unit and frame of ``m.xy`` (and of ``m.sigma`` and ``sigma``).
    pixel_size_mm : float
        Required for ``"px"``.
    principal_point : (float, float)
        ``"px"``: (PX, PY) mm from the upper-left corner, PY down; ``"mm"``: (x0, y0).
    format_mm : (float, float), optional
        Image format; default the extent of the measurements (mm).
    sigma : float
        σ of the coordinates where the file gives none (the file's unit).
    """
    if units not in ("px", "mm"):
        raise InputError(f"units: expected px or mm, got {units!r}", m.source)
    if units == "px":
        if not pixel_size_mm or pixel_size_mm <= 0:
            raise InputError("--units px needs --pixel-size (mm)", m.source)
        xy = m.xy * [pixel_size_mm, -pixel_size_mm]
        sig = np.where(np.isnan(m.sigma), sigma, m.sigma) * pixel_size_mm
        x0, y0 = principal_point[0], -principal_point[1]
    else:
        xy = m.xy.copy()
        sig = np.where(np.isnan(m.sigma), sigma, m.sigma)
        x0, y0 = principal_point
    images = list(dict.fromkeys(m.image))
    points = list(dict.fromkeys(m.point))
    ii = {k: j for j, k in enumerate(images)}
    pi = {k: j for j, k in enumerate(points)}
    fmt = format_mm or tuple(float(v) for v in np.ptp(xy, axis=0).clip(min=1.0))
    block = Block.from_arrays(
        camera_c=[c], camera_x0=[x0], camera_y0=[y0], camera_format_mm=[fmt],
        camera_ids=["camera"], image_camera=np.zeros(len(images), np.int64),
        X0=np.zeros((len(images), 3)), angles=np.zeros((len(images), 3)), image_ids=images,
        xyz=np.zeros((len(points), 3)), point_ids=points,
        obs_image=np.array([ii[k] for k in m.image]), obs_point=np.array([pi[k] for k in m.point]),
        obs_xy=xy, obs_sigma=np.column_stack([sig, sig]),
        meta={"source": m.source, "format": f"measurement CSV ({units})"},
    )  # fmt: skip
    block.images.X0[:] = np.nan  # no approximations: `orientviz solve` computes them
    block.images.angles[:] = np.nan
    block.points.xyz[:] = np.nan
    return block


def run_from_cli(args: argparse.Namespace) -> int:
    """``orientviz import-csv MEASUREMENTS.csv --c MM ... -o OUT.json``."""

    def read(px: float, sig: float) -> Block:
        return block_from_measurements(
            read_measurements(args.file), c=args.c, units=args.units, pixel_size_mm=px,
            principal_point=tuple(args.principal_point or (0.0, 0.0)),
            format_mm=tuple(args.format) if args.format else None, sigma=sig,
        )  # fmt: skip

    from pathlib import Path

    return import_to_problem(args, read, Path(args.file).stem, default_pixel_mm=0.01)
