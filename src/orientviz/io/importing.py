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


def import_to_problem(
    args: argparse.Namespace,
    read: Callable[[float, float], Block],
    name: str,
    *,
    default_pixel_mm: float,
) -> int:
    """Read (``read(pixel_size_mm, sigma_px)``), add control, write ``args.output``.

    Optional arguments (absent = default): ``args.control`` (CSV path),
    ``args.pixel_size`` (mm), ``args.sigma_px`` (px). Returns the exit code.
    """
    from .control import apply_control, read_control
    from .problem import write_problem

    prog = f"orientviz {getattr(args, 'command', None) or 'import'}"
    px = getattr(args, "pixel_size", None) or default_pixel_mm
    sig = getattr(args, "sigma_px", None) or 1.0
    try:
        block = read(px, sig)
        control = getattr(args, "control", None)
        if control:
            block = apply_control(block, read_control(control))
        options = {}
        if np.any(np.nan_to_num(block.points.sigma) > 0):
            options["control"] = "weighted"
        write_problem(
            {"kind": "block", "block": block, "name": name, "options": options}, args.output
        )
    except InputError as exc:
        if exc.source == "<written document>":  # a value the schema refuses after conversion
            exc = InputError(
                f"a converted value is out of range ({exc.where}: {exc.message})",
                str(getattr(args, "file", None) or getattr(args, "directory", "")),
            )
        print(f"{prog}: {exc.one_line()}", file=sys.stderr)
        return 2
    n_control = int(np.sum(block.points.role == CONTROL))
    note = "" if n_control else " — no control points: add them (--control) before adjusting"
    print(f"wrote {args.output}: {block.summary()} (pixel size {px} mm){note}")
    return 0
