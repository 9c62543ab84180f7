"""``orientviz solve FILE [--method bundle|models|polynomial] [--json] [--report PATH]``.

Loads a problem file, solves it with the solver of its kind and prints a readable
report or JSON. ``--report PATH`` also writes the full adjustment report
(:func:`orientviz.report.write_report`): ``*.html`` one self-contained page with
figures, ``*.txt`` fixed-width text. Exit codes: 0 solved and converged, 2 bad input
(one line naming file, place and problem; also a report path that cannot be written or
has another suffix), 3 the adjustment is impossible (datum defect, not determinable) or
did not converge (the report is still printed and written). Never a traceback.
"""

from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

from ..errors import InputError
from ..io.problem import save_problem
from ..io.solve import (
    MISFIT_EXIT,
    adjusted_problem,
    failure,
    limit_hint,
    load_named,
    misfit,
    solve_problem,
)
from ._verdict import verdict


def run_from_cli(args: argparse.Namespace) -> int:
    """Entry point of ``orientviz solve``; returns the exit code: 0 ok, 2 bad input, 3
    adjustment impossible or not converged, :data:`MISFIT_EXIT` (4) the model does not
    fit the data."""
    prog = "orientviz solve"
    report_path = getattr(args, "report", None)
    try:
        if report_path:
            from ._html import report_format  # the report writer: only with --report

            report_format(report_path)  # a wrong suffix fails before the adjustment
        problem = load_named(args.file)
        for name in ("max_iter", "tol", "ftol", "solver", "robust", "robust_scale", "fix", "free"):
            if getattr(args, name, None) is not None:  # the command line wins over the file
                problem.options = dict(problem.options, **{name: getattr(args, name)})
        if getattr(args, "solver", None) is not None and problem.kind != "block":
            raise InputError("--solver applies to block problems only", problem.source)
        solution = solve_problem(problem, getattr(args, "method", None))
        with np.errstate(all="ignore"):
            solution.verdict = verdict(problem, solution)
        text = (
            json.dumps(solution.as_dict(), indent=1, ensure_ascii=False, allow_nan=False)
            if getattr(args, "json", False)
            else solution.as_text()
        )
    except Exception as exc:  # one line and an exit code, never a traceback
        failed = failure(prog, args.file, exc)
        if failed is None:
            raise
        print(failed[0], file=sys.stderr)
        return failed[1]
    adj = solution.adjustment
    at_limit = not adj.converged and str(adj.reason).startswith("reached the maximum")
    if getattr(args, "output", None) and ((adj.converged and not misfit(solution)) or at_limit):
        # at the iteration limit: the last iterate, marked in its description
        try:
            save_problem(adjusted_problem(problem, solution), args.output)
        except InputError as exc:
            print(f"{prog}: {exc.one_line()}", file=sys.stderr)
            return 2
    if report_path:
        from ._html import write_report  # the report writer: only with --report

        try:
            with np.errstate(all="ignore"):
                write_report(problem, solution, report_path)
        except InputError as exc:
            print(f"{prog}: {exc.one_line()}", file=sys.stderr)
            return 2
        print(
            f"{prog}: wrote {report_path} ({os.path.getsize(report_path) / 1024:.0f} KiB, "
            f"{'HTML' if report_path.lower().endswith(('.html', '.htm')) else 'text'} report)",
            file=sys.stderr,
        )
    _print(text)
    if solution.adjustment.converged:  # on failure one line only (the report lists them)
        for note in solution.notes:
            if note.startswith("warning: "):
                print(f"{prog}: warning: {args.file}: {note[9:]}", file=sys.stderr)
    if not solution.adjustment.converged:
        print(
            f"{prog}: {args.file}: the adjustment did not converge: {solution.adjustment.reason}"
            + (limit_hint(problem, getattr(args, "output", None)) if at_limit else ""),
            file=sys.stderr,
        )
        return 3
    if misfit(solution):
        return MISFIT_EXIT
    return 0


def _print(text: str) -> None:
    """Print the report; a closed pipe (``| head``) is not an error."""
    try:
        sys.stdout.write(text + "\n")
        sys.stdout.flush()
    except BrokenPipeError:  # pragma: no cover - depends on the shell
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
