"""The ``orientviz`` command line: a thin layer over the library.

Exit codes: 0 success, 2 bad input (one line names file, place and problem),
3 the adjustment could not be done (datum defect, not determinable, no convergence).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence

from . import __version__
from .errors import OrientvizError

EPILOG = """examples:
  orientviz view                         open the 3D viewer on the default demo
  orientviz solve block.json --json      adjust a problem file, print JSON
  orientviz reproduce geier              a paper's table beside orientviz's numbers
"""


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="orientviz",
        description="Learn, teach and visually debug photogrammetric orientation.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--version", action="version", version=f"orientviz {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")

    s = sub.add_parser(
        "solve",
        help="adjust a problem file and report",
        description="Adjust a problem file (orientviz/1 JSON) and report.",
        epilog="example: orientviz solve similarity_example --json   (a file or a shipped "
        "example: block_strip, block_compact, resection_example, intersection_example)",
    )
    s.add_argument("file", help="problem file, or the name of a shipped example")
    s.add_argument("--method", choices=["bundle", "models", "polynomial"], default=None)
    s.add_argument("--json", action="store_true", help="print the result as JSON")
    s.add_argument(
        "-o",
        "--output",
        metavar="OUT.json",
        default=None,
        help="also write the problem with the adjusted values as start values (frame kinds)",
    )

    v = sub.add_parser(
        "view",
        help="open the 3D viewer (viser) on a file or demo",
        epilog="example: orientviz view block --port 8081",
    )
    v.add_argument("target", nargs="?", default=None, help="problem file or demo name")
    v.add_argument("--host", default="127.0.0.1")
    v.add_argument("--port", type=int, default=8080)
    v.add_argument("--export", metavar="FILE.html", default=None)

    b = sub.add_parser(
        "import-bal",
        help="convert a BAL file to an orientviz problem file",
        epilog="example: orientviz import-bal problem.txt -o block.json",
    )
    b.add_argument("file")
    b.add_argument("-o", "--output", required=True)

    c = sub.add_parser(
        "import-colmap",
        help="convert a COLMAP text model to a problem file",
        epilog="example: orientviz import-colmap sparse/0 -o block.json",
    )
    c.add_argument("directory")
    c.add_argument("-o", "--output", required=True)

    r = sub.add_parser(
        "reproduce",
        help="print a paper's table beside orientviz's result",
        epilog="example: orientviz reproduce geier --json",
    )
    r.add_argument("name", nargs="?", default=None)
    r.add_argument("--json", action="store_true")
    return p


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from . import reproduce

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
        print(reproduce.format_rows(rows))
    return 0


#: command → (module, function); each function takes the parsed arguments, returns an exit code
COMMANDS: dict[str, tuple[str, str]] = {
    "solve": ("orientviz.io.solve", "run_from_cli"),
    "view": ("orientviz.viewer.app", "run_from_cli"),
    "import-bal": ("orientviz.io.bal", "run_from_cli"),
    "import-colmap": ("orientviz.io.colmap", "run_from_cli"),
}


def _dispatch(args: argparse.Namespace) -> int:
    import importlib

    module, func = COMMANDS[args.command]
    try:
        mod = importlib.import_module(module)
    except ModuleNotFoundError as exc:
        if exc.name and exc.name.startswith("orientviz"):
            print(f"orientviz {args.command}: not yet available in this version", file=sys.stderr)
            return 2
        print(
            f"orientviz {args.command}: missing dependency {exc.name!r}; "
            'install with: pip install -e ".[all]"',
            file=sys.stderr,
        )
        return 2
    return int(getattr(mod, func)(args))


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``orientviz`` command; returns the exit code."""
    args = _parser().parse_args(argv)
    try:
        if args.command == "reproduce":
            return _cmd_reproduce(args)
        if args.command in COMMANDS:
            return _dispatch(args)
        _parser().print_help()
        return 0
    except OrientvizError as exc:
        print(f"orientviz: {exc}", file=sys.stderr)
        return exc.exit_code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
