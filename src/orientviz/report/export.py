"""Export the results of a block adjustment: problem file (JSON), CSV tables, COLMAP text.

:func:`export_results` writes, into one folder,

* ``adjusted.json`` — the problem file (``orientviz/1``, kind ``block``) with the
  adjusted orientations and tie points as its values: load it with
  :func:`~orientviz.io.problem.load_problem` or adjust it again with ``orientviz solve``;
* ``images.csv`` and ``points.csv`` — the result tables of this package
  (values, a-posteriori σ, residuals per image and per point);
* ``colmap/`` — the adjusted block as a COLMAP text model
  (:func:`~orientviz.io.colmap.write_colmap`).

``orientviz export FILE -d DIR`` does the same from the command line: it adjusts a
problem file by the bundle method as ``orientviz solve`` does (the file's options; the
datum by its control, or ``--free`` / ``--fix`` as in ``solve``) and writes the results
(``--no-adjust`` exports the file's values without σ).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..adjust.result import Adjustment
from ..block import Block
from ..errors import InputError
from ..io.colmap import write_colmap
from ..io.problem import Units, write_problem
from ..io.safeio import prepare_output_dir
from ..io.solve import MISFIT_EXIT, failure, limit_hint, load_named, misfit, solve_problem
from ..units import RHO
from ._tables import adjusted_block, image_table, point_table

FORMATS = ("json", "csv", "colmap")


def export_results(
    block: Block,
    adj: Adjustment | None,
    directory: str | Path,
    *,
    formats: tuple[str, ...] | list[str] = FORMATS,
    name: str = "",
    angle_unit: str = "gon",
    units: Units | None = None,
) -> dict[str, Path]:
    """Write the results of ``block`` (adjusted by ``adj``) in ``formats`` into ``directory``.

    Parameters
    ----------
    block : Block
        The block that was adjusted (its start values and observations).
    adj : Adjustment or None
        Its bundle adjustment; None exports the block's own values (no σ).
    directory : str or Path
        Target folder (created if needed).
    formats : sequence of {"json", "csv", "colmap"}
        What to write.
    name : str
        Name stored in the problem file.
    angle_unit : str
        Unit of the angles in the CSV tables (default gon).
    units : Units, optional
        The problem file's units: ``adjusted.json`` is written in them (default m, gon,
        mm) and the CSV tables label a reconstruction's model units and give a pixel
        file's residuals in px.

    Returns
    -------
    dict
        ``{"json": path, "images_csv": path, "points_csv": path, "colmap": folder}``
        for what was written.
    """

    unknown = [f for f in formats if f not in FORMATS]
    if unknown:
        raise InputError(f"unknown export format {unknown[0]!r}; expected {', '.join(FORMATS)}")
    d = prepare_output_dir(directory)
    out = block if adj is None else adjusted_block(block, adj)
    written: dict[str, Path] = {}
    if "json" in formats:
        doc = {"kind": "block", "block": out, "name": name or str(block.meta.get("name", ""))}
        write_problem(doc, d / "adjusted.json", units=units)
        written["json"] = d / "adjusted.json"
    if "csv" in formats:
        px = units.pixel_size if units is not None and units.image == "px" else None
        lu = {"length": units.length if units is not None else "m", "pixel_mm": px}
        written["images_csv"] = image_table(block, adj, angle_unit=angle_unit, **lu).to_csv(
            d / "images.csv"
        )
        written["points_csv"] = point_table(block, adj, **lu).to_csv(d / "points.csv")
    if "colmap" in formats:
        write_colmap(out, d / "colmap")
        written["colmap"] = d / "colmap"
    return written


def run_from_cli(args: argparse.Namespace) -> int:
    """``orientviz export FILE -d DIR [--format json,csv,colmap] [--no-adjust] [--free]
    [--fix ID[:PARTS]]``: the bundle adjustment as ``orientviz solve`` runs it (the file's
    options, its datum or the command line's ``--free`` / ``--fix``), then
    :func:`export_results`. Exit 0 written, 2 bad input, 3 adjustment impossible or not
    converged, 4 the model does not fit the data (as ``solve``'s exit 4); nothing written
    unless 0."""
    prog = "orientviz export"
    try:
        problem = load_named(args.file)  # a path, or the name of a shipped example
        if not isinstance(problem.data, Block):
            raise InputError(f"expected a block problem, got kind {problem.kind!r}", args.file)
        for name in ("fix", "free"):
            if getattr(args, name, None) is not None:  # the command line wins over the file
                problem.options = dict(problem.options, **{name: getattr(args, name)})
        block = problem.data
        adj, notes = None, []
        if not args.no_adjust:  # as `orientviz solve` adjusts it (approximations, datum)
            solution = solve_problem(problem, "bundle")
            adj, block = solution.adjustment, solution.start
            notes = [n for n in solution.notes if n.startswith(("free network", "datum"))]
            if not adj.converged:
                at_limit = str(adj.reason).startswith("reached the maximum")
                print(
                    f"{prog}: {args.file}: the adjustment did not converge: {adj.reason}"
                    + (limit_hint(problem, None) if at_limit else ""),
                    file=sys.stderr,
                )
                return 3
            for note in solution.notes:  # the geometry's and the fit's warnings, as solve's
                if note.startswith("warning: "):
                    print(f"{prog}: warning: {args.file}: {note[9:]}", file=sys.stderr)
            if misfit(solution):  # the estimates are not a result: nothing written
                print(f"{prog}: {args.file}: nothing written (the model does not fit the data; "
                      f"orientviz solve {args.file} prints the report)", file=sys.stderr)  # fmt: skip
                return MISFIT_EXIT
        formats = [f.strip() for f in args.format.split(",") if f.strip()]
        u = problem.units  # the CSV's angles in the file's unit (a "dms" file: degrees)
        written = export_results(
            block, adj, args.directory, formats=formats, name=problem.name, units=u,
            angle_unit=u.angle if u.angle in RHO else "deg",
        )  # fmt: skip
    except Exception as exc:  # one line and an exit code, never a traceback
        failed = failure(prog, args.file, exc, rest=f" -d {args.directory}")
        if failed is None:
            raise
        print(failed[0], file=sys.stderr)
        return failed[1]
    for path in written.values():
        print(f"wrote {path}")
    if adj is not None:
        print(f"σ0 = {adj.sigma0:.3f}, redundancy {adj.redundancy}")
    for note in notes:  # the datum the σ refer to
        print(note)
    return 0
