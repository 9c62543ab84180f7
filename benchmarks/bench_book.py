"""Book performance: the whole book built with every notebook executed, and each lesson
notebook executed on its own.

Goals (issue 8): the book builds, notebooks executed, in < 10 min on this machine; each
lesson notebook executes in < 60 s. Printed, never asserted.

* notebook — wall time of ``nbclient`` executing the notebook top to bottom in a fresh
  kernel (kernel start included: what a reader waits for), in a temporary directory,
  ``timeout=600`` per cell. Also the slowest cell (nbclient's cell timing).
* book — wall time of ``python -m sphinx -b html book OUT`` into a fresh output
  directory (no Sphinx cache, so every notebook and the API reference are rebuilt);
  includes the markdown chapters that execute code (command line, problem files...).

The machine is shared: the load average is printed before and after.

Run:  PYTHONPATH=src python benchmarks/bench_book.py [--notebooks-only | --book-only]
"""

from __future__ import annotations

import argparse
import functools
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BOOK_GOAL_S = 600.0
NOTEBOOK_GOAL_S = 60.0


def _env() -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(ROOT / "src")] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p]
    )
    env["MPLBACKEND"] = "module://matplotlib_inline.backend_inline"  # PNG figures, as in the book
    return env


@functools.cache
def _book_extension():
    """book/_ext/orientviz_book.py, for its workaround of a stall in nbclient (#312)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "orientviz_book", ROOT / "book" / "_ext" / "orientviz_book.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def time_notebook(path: Path) -> tuple[float, float, str]:
    """Seconds to execute ``path`` in a fresh kernel; the slowest cell (s, first line).

    Uses the book's shell-polling workaround, as the book build does: without it a cell
    with an Output widget can sleep until the cell timeout (jupyter/nbclient#312).
    """
    import nbclient
    import nbformat

    _book_extension().patch_shell_polling()

    nb = nbformat.read(path, as_version=4)
    with tempfile.TemporaryDirectory(prefix="orientviz-bench-nb-") as tmp:
        old = dict(os.environ)
        os.environ.update(_env())
        try:
            client = nbclient.NotebookClient(
                nb,
                timeout=600,
                kernel_name="python3",
                record_timing=True,
                resources={"metadata": {"path": tmp}},
            )
            t = time.perf_counter()
            client.execute()
            wall = time.perf_counter() - t
        finally:
            os.environ.clear()
            os.environ.update(old)
    slowest, first = 0.0, ""
    for cell in nb.cells:
        timing = cell.get("metadata", {}).get("execution", {})
        a, b = timing.get("iopub.execute_input"), timing.get("shell.execute_reply")
        if cell.cell_type == "code" and a and b:
            s = (
                datetime.fromisoformat(b.replace("Z", "+00:00"))
                - datetime.fromisoformat(a.replace("Z", "+00:00"))
            ).total_seconds()
            if s > slowest:
                src = next((ln for ln in cell.source.splitlines() if ln.strip()), "")
                slowest, first = s, src.strip()[:50]
    return wall, slowest, first


def time_book() -> tuple[float, int, int]:
    """Seconds for a clean book build; exit code; number of warnings in its log."""
    out = Path(tempfile.mkdtemp(prefix="orientviz-bench-book-"))
    try:
        t = time.perf_counter()
        proc = subprocess.run(
            [sys.executable, "-m", "sphinx", "-b", "html", "-q", str(ROOT / "book"), str(out)],
            capture_output=True,
            text=True,
            env=_env(),
        )
        wall = time.perf_counter() - t
    finally:
        shutil.rmtree(out, ignore_errors=True)
    # Sphinx's own warnings ("path:line: WARNING: ..."), not the kernels' stderr chatter
    warnings = len(re.findall(r"(?m)(^|: )(WARNING|ERROR):", proc.stderr))
    if proc.returncode:
        print(proc.stderr[-3000:], file=sys.stderr)
    return wall, proc.returncode, warnings


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--notebooks-only", action="store_true")
    group.add_argument("--book-only", action="store_true")
    args = parser.parse_args()
    stamp = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    print(
        f"# bench_book.py, {stamp}, load average {os.getloadavg()[0]:.1f} (1 min), "
        f"{os.cpu_count()} cores"
    )
    rows = []
    if not args.book_only:
        for path in sorted((ROOT / "notebooks").glob("*.ipynb")):
            wall, slow, first = time_notebook(path)
            ok = "yes" if wall < NOTEBOOK_GOAL_S else "NO"
            rows.append(
                (f"notebook {path.stem}", wall, NOTEBOOK_GOAL_S, ok, f"{slow:.1f} s `{first}`")
            )
            print(f"  {path.stem}: {wall:.1f} s", flush=True)
    if not args.notebooks_only:
        wall, code, warns = time_book()
        ok = "yes" if wall < BOOK_GOAL_S and code == 0 else "NO"
        rows.append(
            (
                "book (clean build)",
                wall,
                BOOK_GOAL_S,
                ok,
                f"exit {code}, {warns} warning/error lines",
            )
        )
    print()
    print("| what | wall s | goal s | within goal | notes (slowest cell / build) |")
    print("| --- | --- | --- | --- | --- |")
    for name, wall, goal, ok, note in rows:
        print(f"| {name} | {wall:.1f} | < {goal:.0f} | {ok} | {note} |")
    print(f"\nload average at the end {os.getloadavg()[0]:.1f} (1 min)")


if __name__ == "__main__":
    main()
