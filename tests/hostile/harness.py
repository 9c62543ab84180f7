"""Run ``orientviz`` on hostile input and check the contract of issue #19.

Each case runs the command line's :func:`orientviz.cli.main` in this process under a
memory ceiling (``RLIMIT_AS``: the address space in use plus a budget) and a hang guard
(an interval timer that raises :class:`Hang`, a ``BaseException`` no handler in orientviz
catches), and checks: the exit code, exactly one line on stderr naming the file (or the
option) the user gave, no traceback, and the folder afterwards: inputs unchanged,
nothing new left behind on failure, only the declared outputs on success.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import os
import resource
import signal
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from orientviz.cli import main

#: seconds a case may take before it counts as a hang
TIMEOUT_S = 60.0
#: address space a case may add, beyond ten times its inputs (bytes)
BUDGET = 600 * 2**20


class Hang(BaseException):
    """Raised by the timer when a case runs longer than :data:`TIMEOUT_S`."""


@dataclass
class Case:
    """One hostile input.

    Attributes
    ----------
    name : str
        Test id, ``"<command>/<format>/<what>"``.
    make : callable
        ``make(folder) -> argv`` writes the inputs into ``folder`` and returns the
        arguments of ``orientviz`` (paths inside ``folder``).
    code : int
        Expected exit code.
    says : tuple of str
        Substrings the stderr line must contain (besides the named file).
    names : str or None
        What the line must name: a path relative to ``folder``, an option such as
        ``"--pixel-size"``, or None (checked by ``says`` alone).
    outputs : tuple of str
        Files/folders (relative) a successful run may create.
    warns : bool
        Exit 0 with warning lines on stderr (each one line, "warning" in it).
    post : callable, optional
        ``post(folder)`` checks the outputs of a successful run (e.g. HTML escaping).
    """

    name: str
    make: Callable[[Path], list[str]]
    code: int
    says: tuple[str, ...] = ()
    names: str | None = None
    outputs: tuple[str, ...] = ()
    warns: bool = False
    post: Callable[[Path], None] | None = field(default=None)

    def __str__(self) -> str:  # pytest id
        return self.name


def _address_space() -> int:
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")


def snapshot(folder: Path) -> dict[str, str]:
    """Relative path → content hash (files) or ``"dir"`` of everything under ``folder``."""
    out = {}
    for p in sorted(folder.rglob("*")):
        rel = str(p.relative_to(folder))
        if p.is_symlink() or not (p.is_file() or p.is_dir()):
            out[rel] = "special"
        elif p.is_dir():
            out[rel] = "dir"
        else:
            out[rel] = hashlib.sha1(p.read_bytes()).hexdigest()
    return out


def _input_bytes(folder: Path) -> int:
    return sum(p.stat().st_size for p in folder.rglob("*") if p.is_file() and not p.is_symlink())


def run_main(argv: list[str], *, budget: int, timeout: float = TIMEOUT_S) -> tuple[int, str, str]:
    """``main(argv)`` under an address-space ceiling and a hang guard → (code, out, err)."""
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    limit = _address_space() + budget
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)

    def _alarm(signum, frame):
        raise Hang(f"orientviz {' '.join(argv)} ran longer than {timeout} s")

    old = signal.signal(signal.SIGALRM, _alarm)
    out, err = io.StringIO(), io.StringIO()
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(argv)
            except SystemExit as exc:  # argparse
                code = exc.code if isinstance(exc.code, int) else 2
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))
    return int(code), out.getvalue(), err.getvalue()


def check_case(case: Case, folder: Path) -> None:
    """Run ``case`` in ``folder`` and assert the contract (see the module docstring)."""
    folder.mkdir(parents=True, exist_ok=True)
    argv = case.make(folder)
    before = snapshot(folder)
    budget = BUDGET + 10 * _input_bytes(folder)
    cwd = os.getcwd()
    os.chdir(folder)  # relative outputs (and stray files) land in the case's folder
    try:
        code, out, err = run_main(argv, budget=budget)
    finally:
        os.chdir(cwd)
    lines = err.splitlines()
    context = f"orientviz {' '.join(argv)}\nstderr:\n{err}"
    assert "Traceback" not in err, context
    assert "internal error" not in err, context
    assert "too large for this machine" not in err, context  # a MemoryError = a blow-up
    assert code == case.code, f"exit {code}, expected {case.code}\n{context}"
    after = snapshot(folder)
    changed = [k for k, v in before.items() if after.get(k) != v]
    assert not changed, f"inputs changed or removed: {changed}\n{context}"
    new = sorted(set(after) - set(before))
    if code == 0:
        allowed = [o for o in case.outputs]
        stray = [n for n in new if not any(n == a or n.startswith(a + "/") for a in allowed)]
        assert not stray, f"unexpected files {stray}\n{context}"
        # a written report is announced on stderr ("orientviz solve: wrote r.html (…)")
        lines = [ln for ln in lines if not ln.startswith(f"orientviz {argv[0]}: wrote ")]
        if case.warns:
            assert lines and all("warning" in ln for ln in lines), context
        else:
            assert not lines, context
        if case.post is not None:
            case.post(folder)
        return
    assert not new, f"a failed run left {new}\n{context}"
    assert len(lines) == 1, f"expected one line on stderr, got {len(lines)}\n{context}"
    line = lines[0]
    assert line.startswith("orientviz"), context
    if case.names is not None:
        named = case.names if case.names.startswith("-") else str(folder / case.names)
        if not case.names.startswith("-") and named not in line:
            named = case.names  # a shipped example or a relative name
        assert named in line, f"{named!r} not named\n{context}"
    for s in case.says:
        assert s in line, f"{s!r} not said\n{context}"
