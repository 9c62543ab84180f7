"""The ``orientviz`` command line: a thin layer over the library.

Every command is one row of :data:`COMMANDS`: where its code lives (imported only when
the command runs), a one-line description, its arguments and worked examples. The
parser and both levels of ``--help`` are built from that table, so a new command is one
new row.

Exit codes: 0 success, 2 bad input (one line names file, place and problem) or a
missing optional package (the line names the extra to install), 3 the adjustment
could not be done (datum defect, not determinable, no convergence).
Every command ends with one of them and one line on stderr, never a traceback (unless
``--debug``). Numbers on the command line are checked by the parser
(:func:`finite_float`, :func:`positive_float`), input files by
:mod:`orientviz.io.safeio` (regular files under ``--max-size``). The command sets
``OPENBLAS_THREAD_TIMEOUT=4`` unless the environment sets it (:func:`quiet_blas_workers`;
``OPENBLAS_THREAD_TIMEOUT=28`` is OpenBLAS's own default).
"""

from __future__ import annotations

import argparse
import atexit
import gc
import importlib
import json
import math
import os
import sys
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, NoReturn, TextIO

from . import __version__
from .errors import OrientvizError, printable
from .io.safeio import input_limit, parse_size


@dataclass(frozen=True)
class Arg:
    """One ``add_argument`` call: its names and keyword arguments."""

    names: tuple[str, ...]
    options: dict[str, Any] = field(default_factory=dict)


def arg(*names: str, **options: Any) -> Arg:
    """Shorthand for :class:`Arg` (the same signature as ``add_argument``)."""
    return Arg(names, options)


def finite_float(text: str) -> float:
    """An argparse type: a finite number (``nan``, ``inf``, ``1e999`` are refused)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def positive_float(text: str) -> float:
    """An argparse type: a finite number > 0."""
    value = finite_float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def float_between(low: float, high: float, unit: str = ""):
    """An argparse type: a finite number in [low, high] (``unit`` for the message)."""

    def parse(text: str) -> float:
        value = finite_float(text)
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(
                f"expected a number from {low:g} to {high:g}{' ' + unit if unit else ''}, "
                f"got {text!r}"
            )
        return value

    parse.__name__ = f"float_between({low:g}, {high:g})"
    return parse


def iteration_count(text: str) -> int:
    """An argparse type: a number of iterations 1–1000."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if not 1 <= value <= 1000:
        raise argparse.ArgumentTypeError(f"expected 1..1000 iterations, got {text!r}")
    return value


def port_number(text: str) -> int:
    """An argparse type: a TCP port 0–65535 (0 = any free port)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a port number, got {text!r}") from None
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"expected a port in 0..65535, got {text!r}")
    return value


def byte_size(text: str) -> int:
    """An argparse type: a size such as ``200M``, ``2G`` or ``4096`` (bytes)."""
    try:
        return parse_size(text)
    except (ValueError, IndexError):
        raise argparse.ArgumentTypeError(
            f"expected a size such as 200M or 2G, got {text!r}"
        ) from None


@dataclass(frozen=True)
class Command:
    """A subcommand of ``orientviz``.

    Attributes
    ----------
    module, function : str
        ``function(args: argparse.Namespace) -> int`` in ``module`` runs the command and
        returns the exit code; the module is imported only when the command runs.
    help : str
        One line for ``orientviz --help``.
    description : str
        The paragraph at the top of ``orientviz CMD --help``.
    examples : tuple of (str, str)
        ``(invocation, what it does)``; the first one is shown in ``orientviz --help``.
        Every invocation must parse (tests/cli/test_help.py checks it).
    arguments : tuple of Arg
    serves : bool
        Whether the command runs until it is stopped (a server): its process keeps
        Python's cyclic garbage collector (:func:`pause_collector`).
    """

    module: str
    function: str
    help: str
    description: str
    examples: tuple[tuple[str, str], ...]
    arguments: tuple[Arg, ...] = ()
    serves: bool = False


#: the options both importers (BAL, COLMAP) take
IMPORT_OPTIONS: tuple[Arg, ...] = (
    arg("-o", "--output", required=True, metavar="OUT.json", help="problem file to write"),
    arg("--control", metavar="CSV", default=None,
        help="control points: CSV id,X,Y,Z[,sX,sY,sZ,role] keyed by point id"),
    arg("--pixel-size", type=float_between(1e-5, 10.0, "mm"), default=None, metavar="MM",
        help="pixel size in mm (default 0.01)"),
    arg("--sigma-px", type=float_between(1e-6, 1e6, "px"), default=None, metavar="PX",
        help="a-priori sigma of the image coordinates in pixels (default 1)"),
)  # fmt: skip

#: The datum options of ``solve`` and ``export`` (``options.fix`` / ``options.free`` of the file)
DATUM_OPTIONS: tuple[Arg, ...] = (
    arg(
        "--fix",
        action="append",
        default=None,
        metavar="ID[:PARTS]",
        help="datum: hold image ID (all six, or PARTS of X0,Y0,Z0,omega,phi,kappa) or "
        "point ID (X,Y,Z) at its given values; repeatable (overrides options.fix)",
    ),
    arg(
        "--free",
        action="store_true",
        default=None,
        help="free network: control and check points become tie points; datum by "
        "minimum constraints (the image pair with the most shared points times base "
        "length: one image held, one base component of the other), or by --fix; "
        "sigmas refer to that datum, the optimum does not depend on it (options.free)",
    ),
)

#: name → Command; the order is the order of ``orientviz --help``
COMMANDS: dict[str, Command] = {
    "solve": Command(
        "orientviz.report.solve",
        "run_from_cli",
        help="adjust a problem file (orientviz/1 JSON) and print a report",
        description="Adjust a problem file (orientviz/1 JSON) and print a report: sigma0, "
        "redundancy, estimated values with standard deviations, the largest normalised "
        "residuals. FILE may also be the name of a shipped example (block_strip, "
        "block_compact, resection_example, intersection_example, similarity_example, "
        "pair_example, dbat_sxb, dbat_camcal, ...). A camera of a block may be calibrated "
        'with it: cameras[] may give "model": "backward" (DBAT, PhotoModeler) or '
        '"forward" (OpenCV) with the lens terms as, sk, K1-K3, P1, P2 (k1-k3, p1, p2), '
        'each parameter free ("free": [...]), weighted ("sigma": {name: σ}) or '
        'fixed, or "additional": "ebner12" | "gruen44" | "brown"; image '
        "units mm, um or px (with units.pixel_size in mm; pixels count y downwards). Exit "
        "0 ok, 2 bad input, 3 adjustment impossible or not converged, 4 the model does not "
        "fit the data (sigma0 far above 1 with many flagged observations: the report is "
        "printed, the warning names the likely causes, -o writes nothing).",
        examples=(
            ("orientviz solve block_strip", "report on a shipped example block (bundle)"),
            ("orientviz solve resection_example --json", "the same report as JSON"),
            ("orientviz solve block_compact --method models", "independent models instead"),
            ("orientviz solve block.json -o adjusted.json", "also save the adjusted values"),
            ("orientviz solve block_strip --report report.html", "full report (or .txt)"),
            (
                "orientviz solve dbat_sxb --max-iter 50 --tol 1e-6",
                "solver options (override options.max_iter / options.tol of the file)",
            ),
            (
                "orientviz solve dbat_camcal",
                "calibrate a real camera: its cameras[0] has "
                '"model": "backward", "free": ["c", "x0", "y0", "as", '
                '"K1", "K2", "K3", "P1", "P2"], units px',
            ),
            (
                "orientviz solve dbat_sxb --robust huber",
                "robust bundle: Huber loss, scale 1.345 sigma (options.robust)",
            ),
            (
                "orientviz solve dbat_sxb --robust cauchy --robust-scale 3",
                "Cauchy loss with scale 3 sigma (options.robust_scale)",
            ),
            (
                "orientviz solve dbat_sxb --free",
                "free network: control as tie points, datum by minimum constraints (options.free)",
            ),
            (
                "orientviz solve dbat_sxb --free --fix 8811 --fix 8938:Y0",
                "datum by image 8811 and Y0 of image 8938 held at their given values (options.fix)",
            ),
        ),
        arguments=(
            arg("file", help="problem file, or the name of a shipped example"),
            arg(
                "--method",
                choices=["bundle", "models", "polynomial"],
                default=None,
                help="block adjustment method (blocks only; default bundle)",
            ),
            arg("--json", action="store_true", help="print the result as JSON"),
            arg(
                "--max-iter",
                type=iteration_count,
                default=None,
                metavar="N",
                help="maximum number of iterations (overrides options.max_iter of the file); a "
                "robust run (--robust) may take 4 times as many, its reweighted steps included",  # ROBUST_ITER_FACTOR
            ),
            arg(
                "--tol",
                type=positive_float,
                default=None,
                metavar="T",
                help="stop when every correction is below T times its sigma (overrides "
                "options.tol; default 5e-3 for blocks)",
            ),
            arg(
                "--ftol",
                type=float_between(0.0, 0.1),
                default=None,
                metavar="F",
                help="also stop when a step lowers vTPv by less than F of its value (Ceres's "
                "function tolerance; overrides options.ftol; default 0 = off, 1e-6 in files "
                "written by import-bal / import-colmap)",
            ),
            arg(
                "--robust",
                choices=["none", "huber", "cauchy", "soft_l1"],
                default=None,
                help="robust loss of each ray inside the bundle's iterations (as Ceres's): "
                "huber and soft_l1 bound, cauchy redescends the influence of large "
                "residuals (overrides options.robust; default none)",
            ),
            arg(
                "--robust-scale",
                type=positive_float,
                default=None,
                metavar="K",
                help="scale of the robust loss in units of the observations' sigma (default "
                "1.345 huber and soft_l1, 2.385 cauchy)",
            ),
            *DATUM_OPTIONS,
            arg(
                "--solver",
                choices=["auto", "banded", "dense", "sparse", "reference"],
                default=None,
                help="solver of the bundle's reduced camera system (overrides options.solver; "
                "default auto: banded for strips, dense for small or densely connected "
                "networks, sparse (nested-dissection multifrontal Cholesky) otherwise; the "
                "report names the choice); reference: the textbook iteration, small blocks",
            ),
            arg(
                "-o",
                "--output",
                metavar="OUT.json",
                default=None,
                help="also write the problem with the adjusted values as start values "
                "(frame kinds)",
            ),
            arg(
                "--report",
                metavar="PATH",
                default=None,
                help="also write an adjustment report: PATH.html (with figures) or PATH.txt",
            ),
        ),
    ),
    "view": Command(
        "orientviz.viewer.app",
        "run_from_cli",
        help="open the 3D viewer (viser, in the browser) on a demo or a problem file",
        description="Open the 3D viewer on a demo (block, pair, radar, design: the block "
        "design studio) or a problem file and serve it on http://HOST:PORT until Ctrl-C; "
        "--export writes a static HTML page instead. FILE may be a shipped data set's name, "
        "or dbat_roma (DBAT's ROMA bundle: 60 images, 90 561 image points). Large blocks "
        "open without the precision (the panel offers it); a large imported model with "
        "every start value given opens at those values while it is solved in the background.",
        examples=(
            ("orientviz view", "the default demo on http://127.0.0.1:8080"),
            ("orientviz view pair --port 8081", "the relative-orientation demo, another port"),
            ("orientviz view block.json", "a block problem file"),
            (
                "orientviz view block.json --free --export free.html",
                "a model without control (an imported COLMAP/BAL model) as a free network",
            ),
            ("orientviz view radar --export radar.html", "write a static page, no server"),
            (
                "orientviz view design block_strip --export design.html",
                "the design studio on a problem file (a static page)",
            ),
        ),
        arguments=(
            arg("target", nargs="?", default=None, help="problem file or demo name"),
            arg(
                "file",
                nargs="?",
                default=None,
                help="after `design`: a block problem file (or data set) to plan from",
            ),  # fmt: skip
            arg("--host", default="127.0.0.1", help="interface to serve on (default 127.0.0.1)"),
            arg("--port", type=port_number, default=8080, help="port (default 8080)"),
            arg("--export", metavar="FILE.html", default=None, help="write a static HTML page"),
            arg(
                "--fix",
                action="append",
                default=None,
                metavar="ID[:PARTS]",
                help="datum of a problem file, as in solve (overrides options.fix)",
            ),
            arg(
                "--free",
                action="store_true",
                default=None,
                help="free network, as in solve (options.free): e.g. an imported COLMAP or BAL "
                "model",
            ),
            arg(
                "--max-iter",
                type=iteration_count,
                default=None,
                metavar="N",
                help="maximum number of iterations, as in solve (overrides options.max_iter)",
            ),
        ),
        serves=True,
    ),
    "import-bal": Command(
        "orientviz.io.bal",
        "run_from_cli",
        help="convert a BAL (Bundle Adjustment in the Large) file to a problem file",
        description="Convert a BAL problem (text) to an orientviz/1 block problem file in "
        "pixels: each BAL camera is a camera with the forward lens model (c = f, k1, k2; "
        "the observations stay the file's distorted pixels, y up), and f, k1, k2 are "
        "refined per camera as the BAL problem defines them (--fix-lens holds them). BAL "
        "has no control: solve with --free (or --fix, or add --control here). The file "
        "gets options.damping = trust and options.ftol = 1e-6 (Ceres's stopping rule). FILE "
        "may be bz2-compressed, or `ladybug`: the shipped BAL problem-49-7776.",
        examples=(
            ("orientviz import-bal problem-49-7776-pre.txt -o block.json", "convert"),
            (
                "orientviz import-bal problem-49-7776-pre.txt --fix-lens -o block.json",
                "only poses and points adjusted",
            ),
            ("orientviz import-bal ladybug -o ladybug.json", "the shipped real BAL problem"),
        ),  # fmt: skip
        arguments=(
            arg("file", help="BAL text file"),
            arg(
                "--fix-lens",
                action="store_true",
                help="hold f, k1, k2 of every camera at the file's values (default: refined)",
            ),
            *IMPORT_OPTIONS,
        ),  # fmt: skip
    ),
    "export-bal": Command(
        "orientviz.io.bal",
        "run_export",
        help="write a block problem file as a BAL file (cameras f, k1, k2)",
        description="Write a block problem file as a BAL text file: angle-axis poses, f = "
        "c / pixel size and k1, k2 of each camera's forward lens model (0 without one), "
        "observations in pixels about the image centre, y up. With a file written by "
        "`orientviz solve ... -o`, the adjusted values. Pixel size: the file's "
        "units.pixel_size when its image unit is px, else --pixel-size (default 0.01 mm).",
        examples=(
            (
                "orientviz export-bal block.json -o block.bal",
                "write a BAL file (after "
                "`orientviz solve block.json --free -o block.json`: the adjusted values)",
            ),
        ),
        arguments=(
            arg("file", help="block problem file, or the name of a shipped example"),
            arg("-o", "--output", required=True, metavar="OUT.bal", help="BAL file to write"),
            arg(
                "--pixel-size",
                type=float_between(1e-5, 10.0, "mm"),
                default=None,
                metavar="MM",
                help="pixel size in mm (default: the file's, else 0.01)",
            ),
        ),  # fmt: skip
    ),
    "import-colmap": Command(
        "orientviz.io.colmap",
        "run_from_cli",
        help="convert a COLMAP model (text or binary) to a problem file",
        description="Convert a COLMAP model (a folder with cameras.txt, images.txt and "
        "points3D.txt, or cameras.bin, images.bin and points3D.bin) to an orientviz/1 block "
        "problem file, keeping only keypoints matched to a 3D point; SIMPLE_PINHOLE, "
        "PINHOLE, SIMPLE_RADIAL, RADIAL and OPENCV cameras are mapped exactly. By default "
        "the file keeps COLMAP's objective: observations in COLMAP's distorted pixels, "
        "each camera a forward lens model with focal length and distortion free as "
        "COLMAP's bundle adjuster refines them (principal point held), sigma in pixels so "
        "sigma0 reads as the pixel RMS; --fix-lens holds the cameras, --undistort writes "
        "undistorted observations of distortion-free cameras instead. A point matched "
        "twice in one image keeps its first keypoint (the count is printed). --control "
        "adds control points from a CSV keyed by POINT3D_ID. DIRECTORY may be `axe`: the "
        "shipped COLMAP model of an axe photographed on a turntable (52 images).",
        examples=(
            ("orientviz import-colmap sparse/0 -o block.json", "convert"),
            ("orientviz import-colmap axe -o axe.json", "the shipped real COLMAP model"),
            ("orientviz import-colmap sparse/0 --fix-lens -o block.json", "cameras held"),
        ),
        arguments=(
            arg("directory", help="folder of the COLMAP model (text or binary), or `axe`"),
            arg(
                "--fix-lens",
                action="store_true",
                help="hold the cameras (focal length, distortion) at COLMAP's values",
            ),
            arg(
                "--undistort",
                action="store_true",
                help="undistorted observations, distortion-free cameras (held)",
            ),
            *IMPORT_OPTIONS,
        ),  # fmt: skip
    ),
    "import-csv": Command(
        "orientviz.io.measurements",
        "run_from_cli",
        help="convert image measurements from a CSV table (image,point,x,y[,sigma]) to a problem file",
        description="Convert image measurements (a CSV with header image,point,x,y[,sigma], "
        "one row per image point, e.g. a PhotoModeler/DBAT table) of one camera to an "
        "orientviz/1 block problem file. --units px (default): pixels from the upper-left "
        "corner, y down, converted with --pixel-size; --principal-point PX PY in mm from "
        "that corner (PY down). --units mm: orientviz's image frame (mm, y up). "
        "--control adds control/check points (CSV id,X,Y,Z[,sX,sY,sZ,role]); the "
        "orientations are computed by `orientviz solve`. --sigma-px is the sigma in the "
        "file's unit where a row gives none.",
        examples=(
            (
                "orientviz import-csv marks.csv --c 123.9392 --pixel-size 0.006 "
                "--principal-point 26.577 38.811 --control control.csv -o block.json",
                "pixel measurements of an aerial camera with control",
            ),
        ),  # fmt: skip
        arguments=(
            arg("file", help="measurement CSV: image,point,x,y[,sigma]"),
            arg(
                "--c",
                type=positive_float,
                required=True,
                metavar="MM",
                help="principal distance in mm",
            ),
            arg(
                "--units",
                choices=["px", "mm"],
                default="px",
                help="unit and frame of x, y (default px: upper-left origin, y down)",
            ),
            arg(
                "--principal-point",
                type=finite_float,
                nargs=2,
                default=None,
                metavar=("PX", "PY"),
                help="principal point in mm (px units: from the upper-left corner, PY down)",
            ),
            arg(
                "--format",
                type=positive_float,
                nargs=2,
                default=None,
                metavar=("W", "H"),
                help="image format in mm (default: the extent of the measurements)",
            ),
            *IMPORT_OPTIONS,
        ),  # fmt: skip
    ),
    "export": Command(
        "orientviz.report.export",
        "run_from_cli",
        help="adjust a block problem file and export the results (JSON, CSV, COLMAP text)",
        description="Adjust a block problem file by the bundle method, as `orientviz solve` "
        "does (the file's options; datum by its control, --free or --fix), and write into "
        "DIR: adjusted.json (the problem with the adjusted values), images.csv and "
        "points.csv (values, standard deviations, residuals per image and point) and colmap/ "
        "(COLMAP text model). --no-adjust exports the file's own values.",
        examples=(
            ("orientviz export block_strip -d results", "adjust a shipped example, write all"),
            (
                "orientviz export block.json -d results --free",
                "a model without control (an imported COLMAP or BAL model) as a free network",
            ),
            (
                "orientviz export block.json -d results --format csv --no-adjust",
                "only the CSV tables of the file's values",
            ),
        ),
        arguments=(
            arg("file", help="block problem file, or the name of a shipped example"),
            arg("-d", "--directory", required=True, metavar="DIR", help="folder to write into"),
            arg(
                "--format",
                default="json,csv,colmap",
                help="comma-separated: json, csv, colmap (default all)",
            ),
            arg("--no-adjust", action="store_true", help="export the values as they are"),
            *DATUM_OPTIONS,
        ),
    ),
    "reproduce": Command(
        "orientviz.cli",
        "run_reproduce",
        help="print a paper's table beside orientviz's numbers",
        description="Reproduce a table or figure of one of the source papers and print the "
        "paper's numbers beside orientviz's. Without NAME: list what can be reproduced.",
        examples=(
            ("orientviz reproduce geier", "Geier 1973, Fig. 8: radar orientation tasks"),
            ("orientviz reproduce", "list the reproductions"),
            ("orientviz reproduce kovarik --json", "as JSON"),
            ("orientviz reproduce kovarik --wide", "one line per row (wider than 100 columns)"),
        ),
        arguments=(
            arg("name", nargs="?", default=None, help="reproduction (omit to list them)"),
            arg("--json", action="store_true", help="print the rows as JSON"),
            arg(
                "--wide",
                action="store_true",
                help="one line per row however long (default: blocks wrapped to 100 columns "
                "when the table is wider)",
            ),
        ),  # fmt: skip
    ),
}


def _examples(cmd: Command) -> str:
    width = max(len(inv) for inv, _ in cmd.examples)
    rows = "\n".join(f"  {inv:{width}s}   {what}" for inv, what in cmd.examples)
    return f"examples:\n{rows}\n"


def _overview() -> str:
    width = max(len(n) for n in COMMANDS)
    rows = []
    for name, cmd in COMMANDS.items():
        rows.append(f"  {name:{width}s}   {cmd.help}")
        rows.append(f"  {'':{width}s}     e.g. {cmd.examples[0][0]}")
    rows.append("\n'orientviz COMMAND --help' shows a command's options and more examples.")
    return "commands:\n" + "\n".join(rows) + "\n"


#: options every command takes (added to each subcommand's parser)
COMMON_OPTIONS: tuple[Arg, ...] = (
    arg("--debug", action="store_true",
        help="show the Python traceback of an unexpected error (for bug reports)"),
    arg("--max-size", type=byte_size, default=None, metavar="SIZE",
        help="largest input file to read, e.g. 200M or 2G (default 512M)"),
)  # fmt: skip


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line on stderr (exit code 2)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: {message} (see {self.prog} --help)\n")


def _parser(only: str | None = None) -> argparse.ArgumentParser:
    """The parser of the command line; ``only``: the command named first on it, the one
    subparser built (a command's arguments never reach another's; ``--help`` and every
    other first word get all of them)."""
    p = _Parser(
        prog="orientviz",
        description="Learn, teach and visually debug photogrammetric orientation.",
        epilog=_overview(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--version", action="version", version=f"orientviz {__version__}")
    sub = p.add_subparsers(
        dest="command",
        metavar="COMMAND",
        help="one of the commands below",
        parser_class=_Parser,
    )
    for name, cmd in COMMANDS.items() if only not in COMMANDS else [(only, COMMANDS[only])]:
        s = sub.add_parser(
            name,
            description=textwrap.fill(cmd.description, 88),
            epilog=_examples(cmd),
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        for a in (*cmd.arguments, *COMMON_OPTIONS):
            s.add_argument(*a.names, **a.options)
    return p


def run_reproduce(args: argparse.Namespace) -> int:
    """``orientviz reproduce [NAME] [--json]``; returns the exit code."""
    from . import reproduce  # the papers' tables: only for this command (keeps others' start fast)

    if args.name is None:
        for k, d in reproduce.available().items():
            print(f"{k:12s} {d}")
        return 0
    try:
        rows = reproduce.run(args.name)
    except KeyError as exc:
        print(f"orientviz reproduce: {exc.args[0]}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps([r.as_dict() for r in rows], indent=1, default=str))
    else:
        print(reproduce.format_rows(rows, None if getattr(args, "wide", False) else 100))
    return 0


#: optional packages → the extra of pyproject.toml that installs them
OPTIONAL_PACKAGES: dict[str, str] = {
    "matplotlib": "plot",
    "viser": "viewer",
    "ipywidgets": "notebooks",
    "jupyterlab": "notebooks",
    "ipykernel": "notebooks",
    "sphinx": "book",
    "myst_nb": "book",
    "pycolmap": "bench",
    "cv2": "bench",
}

#: a command whose every optional package comes with one extra
COMMAND_EXTRAS: dict[str, str] = {"view": "viewer"}


def missing_package_message(command: str, exc: ModuleNotFoundError) -> str | None:
    """The one line that names the extra to install for a missing package.

    Parameters
    ----------
    command : str
        The subcommand that needed the package.
    exc : ModuleNotFoundError
        What the import raised.

    Returns
    -------
    str or None
        ``None`` if the missing module is orientviz's own (a bug, not an install
        problem).
    """
    top = (exc.name or "").split(".")[0]
    if not top or top == "orientviz":
        return None
    extra = OPTIONAL_PACKAGES.get(top)
    if extra is None:
        return (
            f"orientviz {command}: the package {top!r} is missing although orientviz "
            "needs it; reinstall: pip install orientviz (in a clone: pip install -e .)"
        )
    extra = COMMAND_EXTRAS.get(command, extra)
    return (
        f"orientviz {command}: needs the optional package {top!r}, which is not installed; "
        f'install the extra: pip install "orientviz[{extra}]" '
        f'(in a clone: pip install -e ".[{extra}]")'
    )


def _dispatch(args: argparse.Namespace) -> int:
    cmd = COMMANDS[args.command]
    try:
        mod = importlib.import_module(cmd.module)
    except ModuleNotFoundError as exc:
        if exc.name and exc.name.startswith("orientviz"):
            print(f"orientviz {args.command}: not yet available in this version", file=sys.stderr)
            return 2
        raise
    return int(getattr(mod, cmd.function)(args))


#: OpenBLAS's idle wait of a command (``OPENBLAS_THREAD_TIMEOUT``: 2**N CPU cycles, N in
#: 4 … 30; OpenBLAS's own default is 2**28, about 0.1 s).
BLAS_THREAD_TIMEOUT: str = "4"


def quiet_blas_workers() -> None:
    """Let OpenBLAS's worker threads sleep as soon as they are idle, in this process.

    An OpenBLAS worker busy-waits for new work for ``OPENBLAS_THREAD_TIMEOUT`` (2**28
    cycles by default) after it starts and after each product. A command loads two
    OpenBLAS libraries (NumPy's and SciPy's) and runs bundles of up to 500 images on one
    BLAS thread (:mod:`orientviz.blas`), so on a machine with more than one core those
    workers mostly spin without work. Sets :data:`BLAS_THREAD_TIMEOUT` unless the
    environment has its own value; effective only before NumPy is imported (``import
    orientviz`` loads no NumPy). The results do not change: the setting only decides
    when a worker without work goes to sleep.
    """
    os.environ.setdefault("OPENBLAS_THREAD_TIMEOUT", BLAS_THREAD_TIMEOUT)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``orientviz`` command; returns the exit code (0, 2 or 3).

    Bad input ends with exit code 2, an impossible adjustment with 3, each with one line
    on stderr. An error nobody foresaw is reported in one line too (exit 3, "internal
    error"), with the traceback only under ``--debug``. Without ``argv`` (the command
    itself, its arguments from ``sys.argv``) the process ends here (:func:`end_process`);
    with ``argv`` (a call from Python) the exit code is returned.
    """
    code = _main(argv, own_process=argv is None)
    if argv is None:
        end_process(code)
    return code


def pause_collector(command: str) -> None:
    """Switch Python's cyclic garbage collector off for the rest of a command's process,
    unless the command serves until it is stopped (:attr:`Command.serves`).

    A command's process builds its objects once and keeps most of them to its end (the
    modules of NumPy, SciPy and orientviz, the problem file's document), so the
    collector's passes over them cost time and find few objects held in reference
    cycles. Everything else is freed as before, by reference counting; the process ends by :func:`end_process`. Called only in the command's own
    process (:func:`main` without ``argv``), never for a call from Python.
    """
    cmd = COMMANDS.get(command)
    if cmd is not None and not cmd.serves:
        gc.disable()


def end_process(code: int) -> NoReturn:
    """End the process with exit ``code`` once its output is out, without the
    interpreter's teardown.

    Runs the exit handlers (:mod:`atexit`: logging's flush among them) and flushes
    standard output and error, then leaves by :func:`os._exit`: the freeing of every
    loaded module (NumPy's and SciPy's, about a thousand) is work a finished command
    does not need (benchmarks/README.md). Files are written and closed before this
    (:func:`orientviz.io.safeio.write_atomic`).
    """
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe (`| head`) or a closed stream
            pass
    os._exit(code)


class _ClosedPipeDrops:
    """Standard output whose reader may leave early (``orientviz … | head -1``): once the
    pipe is closed, the rest of the output goes to the null device and the command runs
    to its end (its files written, its exit code kept) instead of failing on a write."""

    def __init__(self, stream: TextIO) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            self._to_null()
            return len(text)

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError:
            self._to_null()

    def _to_null(self) -> None:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, self._stream.fileno())  # the buffered rest is written there too
        os.close(null)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


def _main(argv: Sequence[str] | None, own_process: bool = False) -> int:
    """The work of :func:`main`: parse, dispatch, and turn every failure into one line
    and an exit code (``own_process``: the command's own process, :func:`pause_collector`)."""
    quiet_blas_workers()
    words = sys.argv[1:] if argv is None else list(argv)
    parser = _parser(words[0] if words else None)
    args = parser.parse_args(words)
    if args.command not in COMMANDS:
        parser.print_help()
        return 0
    if own_process:
        pause_collector(args.command)
        if not isinstance(sys.stdout, _ClosedPipeDrops):
            sys.stdout = _ClosedPipeDrops(sys.stdout)
    debug = bool(getattr(args, "debug", False))
    prog = f"orientviz {args.command}"
    try:
        with input_limit(getattr(args, "max_size", None)):
            return _dispatch(args)
    except OrientvizError as exc:
        print(f"{prog}: {_one_line(str(exc))}", file=sys.stderr)
        return exc.exit_code
    except ModuleNotFoundError as exc:
        message = missing_package_message(args.command, exc)
        if debug:
            raise
        if message is not None:
            print(message, file=sys.stderr)
            return 2
        print(
            f"{prog}: internal error: {type(exc).__name__}: {_one_line(str(exc))} "
            "(a bug in orientviz; rerun with --debug and report the traceback)",
            file=sys.stderr,
        )
        return 3
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return 3
    except MemoryError:
        if debug:
            raise
        print(
            f"{prog}: the input is too large for this machine's memory "
            "(use a smaller file or --max-size to refuse such files early)",
            file=sys.stderr,
        )
        return 2
    except RecursionError:
        if debug:
            raise
        print(f"{prog}: the input is nested too deeply", file=sys.stderr)
        return 2
    except Exception as exc:  # the safety net: one line, never a traceback
        if debug:
            raise
        print(
            f"{prog}: internal error: {type(exc).__name__}: {_one_line(str(exc))} "
            "(a bug in orientviz; rerun with --debug and report the traceback)",
            file=sys.stderr,
        )
        return 3


def _one_line(text: str, limit: int = 1000) -> str:
    return printable(text, limit)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
