"""Solve a problem file: :func:`solve_problem` by the solver of its kind, the geometry
checks before it (:func:`check_geometry`), what a solve hands back to a file
(:func:`adjusted_problem`) and whether its model fits (:func:`misfit`); loading by path
or shipped name (:func:`load_named`) and the one-line messages of failures
(:func:`failure`). The command ``orientviz solve``, which prints the solution and writes
reports, is :mod:`orientviz.report.solve`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..block import TIE, Block
from ..errors import AdjustmentError, DatumDefectError, InputError
from ..plausibility import check_block, check_magnitudes, raise_for
from .datasets import resolve_name
from .problem import Problem, load_problem
from .registry import get_kind
from .solution import Solution


def solve_problem(problem: Problem, method: str | None = None, **bundle: Any) -> Solution:
    """Solve a loaded problem by its kind's solver.

    Parameters
    ----------
    problem : Problem
        From :func:`~orientviz.io.problem.load_problem`.
    method : str, optional
        ``"bundle"``, ``"models"`` or ``"polynomial"`` for blocks; None = the default.
    **bundle
        Further keywords of the block bundle (:func:`orientviz.io.kinds.block.adjust_block`),
        e.g. ``precision=False`` (the viewer on a large block); block problems only.

    Raises
    ------
    InputError
        If the method does not apply to the kind, or the solver rejects the data.
    AdjustmentError
        Datum defect, parameters not determinable, breakdown.
    """
    kind = get_kind(problem.kind, problem.source)
    if method is not None and method not in kind.methods:
        allowed = ", ".join(kind.methods) if len(kind.methods) > 1 else "none"
        raise InputError(
            f"--method {method} does not apply to a {kind.name!r} problem (methods: {allowed})",
            problem.source,
        )
    if kind.solve is None:
        raise InputError(f"kind {kind.name!r} cannot be solved by this version", problem.source)
    warnings = check_geometry(problem)
    with np.errstate(all="ignore"):
        solution = kind.solve(problem, method, **bundle) if bundle else kind.solve(problem, method)
    # the checks saw the file's values, not the solution's: say so where both are listed
    solution.notes.extend(f"warning: in the file's values: {f.message}" for f in warnings)
    return solution


def check_geometry(problem: Problem) -> list:
    """The plausibility checks (:mod:`orientviz.plausibility`) of a frame problem.

    Raises the first fatal finding (InputError naming the file and place, or
    AdjustmentError); returns the warnings (also logged). Other kinds: no checks.
    """
    if not isinstance(problem.data, Block):
        return raise_for(check_magnitudes(problem.data), problem.source)
    if problem.columnar:
        place = lambda k: f"observations.x[{k}]"  # noqa: E731
    else:
        place = lambda k: f"observations[{k}]"  # noqa: E731
    u = problem.units
    findings = check_block(
        problem.data, exterior_unknown=problem.kind != "intersection", place=place,
        length=u.length, pixel_mm=u.pixel_size if u.image == "px" else None,
    )  # fmt: skip
    return raise_for(findings, problem.source)


def load_named(name: str) -> Problem:
    """Load a problem file, or a shipped data set by its name (``dbat_sxb``, …)."""
    return load_problem(resolve_name(name))


def failure(prog: str, file: str, exc: BaseException, rest: str = "") -> tuple[str, int] | None:
    """The one-line message and exit code of a problem that cannot be loaded or solved.

    What ``orientviz solve`` and ``orientviz export`` print (and ``orientviz view`` before
    any server starts): 2 bad input, 3 adjustment impossible. None for an exception that
    is not one of these (a bug: the caller re-raises it). ``rest``: the command's further
    arguments after FILE, repeated in the hint on the datum (e.g. ``" -d DIR"``).
    """
    if isinstance(exc, InputError):
        if not exc.source:  # a solver's check: the file is the user's
            exc = InputError(exc.message, file, exc.where)
        return f"{prog}: {exc.one_line()}", 2
    if isinstance(exc, ModuleNotFoundError):  # a solver module of this kind is not there (yet)
        return f"{prog}: {file}: not yet available in this version ({exc.name})", 2
    if isinstance(exc, DatumDefectError) and exc.defect == 7:  # no datum at all: both ways
        return (
            f"{prog}: {file}: adjustment impossible: {exc}; solve it as a free network "
            f"({prog} {file}{rest} --free) or hold images or points at their given values (--fix "
            "IMAGE --fix IMAGE2:X0 — one image and the scale)",
            3,
        )
    if isinstance(exc, AdjustmentError):
        return f"{prog}: {file}: adjustment impossible: {exc}", 3
    if isinstance(exc, ValueError | TypeError | KeyError):  # a library check without InputError
        msg = exc.args[0] if exc.args else type(exc).__name__
        return f"{prog}: {file}: {msg}", 2
    if isinstance(exc, np.linalg.LinAlgError | ArithmeticError):
        return f"{prog}: {file}: adjustment impossible: {exc}", 3
    if isinstance(exc, RecursionError):
        return f"{prog}: {file}: the problem is nested too deeply", 2
    if isinstance(exc, MemoryError):
        return f"{prog}: {file}: the problem is too large for this machine", 2
    return None


#: Exit code of a solve whose model does not fit the data (σ0 far above 1 with a large
#: share of the image coordinates flagged): the report is printed and the warning names
#: the likely causes, but the estimates are not a result (``-o`` writes nothing).
MISFIT_EXIT = 4


def misfit(solution: Solution) -> bool:
    """Whether the solution carries the "model does not fit the data" warning."""
    return any(n.startswith(MISFIT_NOTE) for n in solution.notes)


#: The start of the note of :func:`orientviz.io.kinds.block.misfit_warning`.
MISFIT_NOTE = "warning: the model does not fit the data"


#: The description's marker of a file written at the iteration limit.
LAST_ITERATE_MARK = "[NOT CONVERGED: the last iterate of orientviz solve"


def limit_hint(problem: Problem, output: str | None) -> str:
    """What follows the message of a solve stopped by the iteration limit: the options
    that would help, and where the last iterate went (``-o``)."""
    n = int(problem.options.get("max_iter", 30))
    ftol = float(problem.options.get("ftol", 0.0) or 0.0)
    tips = [f"--max-iter {min(1000, 4 * n)}"]
    if not ftol > 0:
        tips.append(
            "--ftol 1e-6 (stop when a step lowers vTPv by less than 1e-6 of its value, as "
            "Ceres does; weakly determined far points keep large corrections long after the "
            "fit has settled)"
        )
    out = f"; try {' or '.join(tips)}"
    if output:
        out += f"; {output} holds the last iterate (marked NOT CONVERGED in its description)"
    return out


def adjusted_problem(problem: Problem, solution: Solution) -> Problem:
    """The problem with the adjusted orientations and points as its values (frame kinds).

    Images take the adjusted X0 and ω, φ, κ where they were estimated, tie points their
    adjusted coordinates; control and check coordinates and all observations stay as
    given. Raises :class:`InputError` for kinds without images and points (similarity).
    """
    if not isinstance(problem.data, Block):
        raise InputError(
            f"--output writes block, resection and intersection problems, not {problem.kind!r}",
            problem.source,
        )
    block = problem.data.copy()
    im = {k: i for i, k in enumerate(block.images.ids)}
    for k, ident in enumerate(solution.image_ids):
        i = im[ident]
        if np.all(np.isfinite(solution.X0[k])):
            block.images.X0[i] = solution.X0[k]
        if np.all(np.isfinite(solution.angles[k])):
            block.images.angles[i] = solution.angles[k]
    pt = {k: i for i, k in enumerate(block.points.ids)}
    for k, ident in enumerate(solution.point_ids):
        i = pt[ident]
        if block.points.role[i] == TIE and np.all(np.isfinite(solution.xyz[k])):
            block.points.xyz[i] = solution.xyz[k]
    adjusted_cameras(block, getattr(solution.adjustment, "camera", None))
    out = Problem(**{**problem.__dict__, "data": block})
    adj = solution.adjustment
    mark = (
        f"[start values adjusted by orientviz solve ({solution.method})]"
        if adj.converged
        else f"{LAST_ITERATE_MARK} ({solution.method}): {adj.reason}]"
    )
    out.description = (problem.description + " " if problem.description else "") + mark
    return out


def adjusted_cameras(block, cam) -> None:
    """Put a lens model's estimates (``adj.camera``, one group per camera) into the
    block's cameras, in place: c, x0, y0 and the estimated terms of ``cameras.model``
    (nothing without a camera model or estimates)."""
    models = list(getattr(block.cameras, "model", None) or [])
    if cam is None or not models or cam.value.shape[0] != len(models):
        return
    for g, spec in enumerate(models):
        for j, name in enumerate(cam.names):
            if not cam.estimated[j] or not np.isfinite(cam.value[g, j]):
                continue
            v = float(cam.value[g, j])
            if name in ("c", "x0", "y0"):
                getattr(block.cameras, name)[g] = v
            elif spec:
                spec.setdefault("values", {})[name] = v
