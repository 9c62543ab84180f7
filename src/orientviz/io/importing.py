"""The shared part of ``orientviz import-colmap`` and ``orientviz import-bal``.

Both read a foreign model into a :class:`~orientviz.block.Block`, optionally add control
points from a CSV (:mod:`orientviz.io.control`) and write an ``orientviz/1`` block
problem file. Bad input ends with one line naming file and line, exit code 2.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable

import numpy as np

from ..block import CONTROL, Block
from ..errors import InputError
from ..units import MODEL_UNIT
from .problem import Units, write_problem

#: Solver options written into an imported SfM model (BAL, COLMAP): Levenberg-Marquardt
#: with Ceres's trust-region schedule and Ceres's stopping rule on the relative decrease of
#: vᵀPv. Weakly determined points far along nearly parallel rays keep corrections large in
#: their a-priori σ long after the fit has settled; the σ-rule of aerial blocks alone would
#: not stop there.
SFM_OPTIONS: dict = {"damping": "trust", "ftol": 1e-6}


def import_to_problem(
    args: argparse.Namespace,
    read: Callable[[float, float], Block],
    name: str,
    *,
    default_pixel_mm: float,
    options: dict | None = None,
    pixel_units: bool = False,
    lens_note: str = "",
    lens_note_of: Callable[[], str] | None = None,
) -> int:
    """Read (``read(pixel_size_mm, sigma_px)``), add control, write ``args.output``.

    Optional arguments (absent = default): ``args.control`` (CSV path),
    ``args.pixel_size`` (mm), ``args.sigma_px`` (px). ``options`` go into the file's
    ``options``; ``pixel_units`` (an SfM model) writes the image quantities in pixels
    (``units.image = "px"``, angles in degrees: the units SfM users read) instead of mm
    and gon, and :data:`SFM_OPTIONS`;
    ``lens_note`` (or ``lens_note_of()`` after reading) is appended to the one-line
    summary. Returns the exit code.
    """
    prog = f"orientviz {getattr(args, 'command', None) or 'import'}"
    px = getattr(args, "pixel_size", None) or default_pixel_mm
    sig = getattr(args, "sigma_px", None) or 1.0
    try:
        block = read(px, sig)
        control = getattr(args, "control", None)
        if control:
            from .control import apply_control, read_control  # only with --control

            block = apply_control(block, read_control(control))
        options = dict(SFM_OPTIONS if pixel_units else {}, **(options or {}))
        if np.any(np.nan_to_num(block.points.sigma) > 0):
            options["control"] = "weighted"
        # without control the model's scale is arbitrary: its lengths are model units
        length = "m" if control else MODEL_UNIT
        units = Units(length, "deg", "px", px) if pixel_units else Units(length)
        write_problem(
            {"kind": "block", "block": block, "name": name, "options": options, "units": units},
            args.output,
        )
    except InputError as exc:
        if exc.source == "<written document>":  # a value the schema refuses after conversion
            exc = InputError(
                f"a converted value is out of range ({exc.where}: {exc.message})",
                str(getattr(args, "file", None) or getattr(args, "directory", "")),
            )
        print(f"{prog}: {exc.one_line()}", file=sys.stderr)
        return 2
    note = lens_note_of() if lens_note_of is not None else lens_note
    scale = "image coordinates in px" if pixel_units else f"pixel size {px} mm"
    print(f"wrote {args.output}: {block.summary()} ({scale}){note}")
    hint = datum_hint(block, args.output)
    if hint:
        print(hint)
    return 0


def datum_hint(block: Block, output: str) -> str:
    """What the user needs before ``orientviz solve`` on an imported block: the datum.

    An SfM model without control floats in its own frame (7 datum parameters): it is
    solved as a free network (``--free``: minimum constraints) or with chosen images or
    points held (``--fix``), or control is added (``--control`` at import). Empty when
    the block has control points.
    """
    if np.any(block.points.role == CONTROL):
        return ""
    ids = list(block.images.ids) + ["IMAGE", "IMAGE2"]
    return (
        f"datum: no control points — solve it as a free network (orientviz solve {output} "
        f"--free), or hold images or points at their given values (e.g. --fix {ids[0]} "
        f"--fix {ids[1]}:X0 — one image and the scale), or add control at import (--control CSV)"
    )
