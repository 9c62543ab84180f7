"""The command line's own part of ``orientviz import-* … && orientviz solve … --free``.

Issue 28 point 5a asks the two commands end to end for at most twice the library solve.
This bench splits the pair's CPU time into what no Python program that uses NumPy and
SciPy avoids (the floor), the library solve, and orientviz's own part, stage by stage,
for the stripped BAL Ladybug problem (as ``bench_sfm.py`` makes it) and the shipped
COLMAP model ``axe``, at one BLAS thread and at the default threads. Per round, in turn:

* the floor: CPU of ``python -c "import numpy; os._exit(0)"`` (what an import command
  needs before its own work) plus ``python -c "import numpy, scipy.linalg, scipy.sparse,
  scipy.sparse.csgraph, scipy.special; os._exit(0)"`` (what ``solve`` needs); both leave
  without the interpreter's teardown and with OpenBLAS's idle workers asleep, as the
  commands do (``cli.end_process``, ``cli.quiet_blas_workers``);
* the library solve (``bench_sfm.py``'s worker: ``adjust_block(precision=False)`` of the
  loaded problem, the clock around the adjustment only);
* each command as a user runs it (the console script next to this Python, compiled
  modules kept), CPU of the whole process;
* the cold library script (:data:`LIBRARY_SCRIPT`): what a user of the library runs
  instead of the two commands, ``python lib.py`` that imports orientviz, loads the
  problem file and solves it as ``solve --free`` does (the precision included, no report),
  CPU of the whole process (the interpreter's teardown included, as a script has it);
* each command once more inside one fresh process with clocks around its stages
  (:data:`STAGES`): NumPy's, SciPy's and orientviz's imports, reading, building the
  block, the adjustment without its precision, the precision, the verdict, the rest
  (the geometry checks, the solution, the text, writing the file).

``--vs-src DIR`` runs another source tree (e.g. main's) in the same rounds, alternating,
for a before/after of every row. Medians of ``--rounds`` rounds; quote them with
``uptime``'s load. Results in benchmarks/README.md ("the command line's own part").

Usage::

    PYTHONPATH=src python benchmarks/bench_cli.py --rounds 5 [--vs-src /path/src]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
SRC = HERE.parent / "src"
AXE = SRC / "orientviz" / "datasets" / "axe"
LADYBUG = SRC / "orientviz" / "datasets" / "bal" / "problem-49-7776-pre.txt.bz2"
#: What ``solve`` needs from SciPy (the floor's second process imports them).
SCIPY = "scipy.linalg, scipy.sparse, scipy.sparse.csgraph, scipy.special"

#: The stages of a command: (label, module, attribute) wrapped with a CPU clock.
STAGES = {
    "solve": [
        ("read", "orientviz.report.solve", "load_named"),
        ("block", "orientviz.io.kinds.block", "prepare"),
        ("adjust", "orientviz.io.kinds.block", "adjust_block"),
        ("precision", "orientviz.bundle.loop._finish", "bundle_precision"),
        ("verdict", "orientviz.report.solve", "verdict"),
    ],
    "import-bal": [
        ("read", "orientviz.io.bal", "read_bal"),
        ("write", "orientviz.io.importing", "write_problem"),
    ],
    "import-colmap": [
        ("read", "orientviz.io.colmap", "read_colmap"),
        ("write", "orientviz.io.importing", "write_problem"),
    ],
}

#: The cold library script: ``python lib.py FILE`` solving FILE as ``solve FILE --free``.
LIBRARY_SCRIPT = """
import sys
import orientviz as ov
problem = ov.load_problem(sys.argv[1])
problem.options = dict(problem.options, free=True)
solution = ov.solve_problem(problem)
"""

WORKER = r"""
import importlib, json, sys, time
stages = json.loads(sys.argv[1]); argv = sys.argv[2:]
T = time.process_time
out = {}
t = T(); import numpy; out["numpy"] = T() - t
if argv[0] == "solve":
    t = T(); import scipy.linalg, scipy.sparse, scipy.sparse.csgraph, scipy.special
    out["scipy"] = T() - t
t = T()
from orientviz import cli
for _, mod, _ in stages:
    importlib.import_module(mod)
out["orientviz imports"] = T() - t
def clocked(label, f):
    def g(*a, **k):
        t0 = T()
        try:
            return f(*a, **k)
        finally:
            out[label] = out.get(label, 0.0) + T() - t0
    return g
for label, mod, name in stages:
    m = sys.modules[mod]
    setattr(m, name, clocked(label, getattr(m, name)))
import contextlib, io
t = T()
with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
    cli.main(argv)
out["command"] = T() - t
print(json.dumps(out))
"""


def _env(src: str, threads: str, pycache: str) -> dict:
    """The environment of every process of a round: the source tree, compiled modules
    kept, the BLAS threads; OpenBLAS's idle workers sleep at once, as the commands set it
    before NumPy loads (``cli.quiet_blas_workers``), so the floor and the stages' worker
    pay what the commands pay (the library solve is ``bench_sfm.py``'s own worker)."""
    env = dict(os.environ)
    env.setdefault("OPENBLAS_THREAD_TIMEOUT", "4")  # cli.BLAS_THREAD_TIMEOUT
    env["PYTHONPATH"] = os.pathsep.join([str(HERE), src])
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env["PYTHONPYCACHEPREFIX"] = pycache  # compiled modules kept, as an installed package
    for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        env.pop(k, None)
        if threads == "1":
            env[k] = "1"
    return env


def _cpu(cmd: list[str], env: dict) -> float:
    """CPU seconds (user + system) of one child process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, env=env, capture_output=True, check=False)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def one_round(src: str, model: str, threads: str, work: Path) -> dict:
    """Every measurement of one round for one source tree and model."""
    env = _env(src, threads, str(work / "pyc"))
    py, exe = sys.executable, str(Path(sys.executable).parent / "orientviz")
    out_json = str(work / "m.json")
    if model == "ladybug":
        imp = ["import-bal", str(work / "front.bal"), "-o", out_json]
    else:
        imp = ["import-colmap", str(AXE), "-o", out_json]
    solve = ["solve", out_json, "--free"]
    row = {
        "floor import": _cpu([py, "-c", "import numpy, os; os._exit(0)"], env),
        "floor solve": _cpu([py, "-c", f"import numpy, os, {SCIPY}; os._exit(0)"], env),
        "import process": _cpu([exe, *imp], env),
        "solve process": _cpu([exe, *solve], env),
        "cold library script": _cpu([py, "-c", LIBRARY_SCRIPT, out_json], env),
    }
    lib_env = dict(env)
    if "OPENBLAS_THREAD_TIMEOUT" not in os.environ:  # bench_sfm's yardstick as it runs it
        lib_env.pop("OPENBLAS_THREAD_TIMEOUT")
    lib = subprocess.run(
        [py, "-c", "import bench_sfm, json, sys; "
         "print(json.dumps(bench_sfm.run_worker('orientviz', sys.argv[1], sys.argv[2])))",
         out_json, threads],
        env=lib_env, capture_output=True, text=True, check=True,
    )  # fmt: skip
    row["library solve"] = json.loads(lib.stdout.strip().splitlines()[-1])["cpu"]
    for cmd, prefix in ((imp, "import: "), (solve, "solve: ")):
        res = subprocess.run(
            [py, "-c", WORKER, json.dumps(STAGES[cmd[0]]), *cmd],
            env=env, capture_output=True, text=True, check=True,
        )  # fmt: skip
        row.update(
            {prefix + k: v for k, v in json.loads(res.stdout.strip().splitlines()[-1]).items()}
        )
    return row


def derived(r: dict) -> dict:
    """The pair, its floor, orientviz's own part and the solve's stages net of nesting."""
    d = dict(r)
    d["pair"] = r["import process"] + r["solve process"]
    d["floor"] = r["floor import"] + r["floor solve"]
    d["pair ÷ library"] = d["pair"] / r["library solve"]
    d["floor ÷ library"] = d["floor"] / r["library solve"]
    d["(floor + library) ÷ library"] = (d["floor"] + r["library solve"]) / r["library solve"]
    d["orientviz's own part"] = d["pair"] - d["floor"] - r["library solve"]
    d["cold library script ÷ library"] = r["cold library script"] / r["library solve"]
    d["pair ÷ cold library script"] = d["pair"] / r["cold library script"]
    d["solve: adjust without precision"] = r["solve: adjust"] - r.get("solve: precision", 0.0)
    staged = sum(r.get("solve: " + k, 0.0) for k in ("read", "block", "adjust", "verdict"))
    d["solve: rest of the command"] = r["solve: command"] - staged
    staged = sum(r.get("import: " + k, 0.0) for k in ("read", "write"))
    d["import: rest of the command"] = r["import: command"] - staged
    return d


ROWS = [
    "floor import", "floor solve", "floor", "library solve",
    "import process", "solve process", "pair", "pair ÷ library", "floor ÷ library",
    "(floor + library) ÷ library", "orientviz's own part",
    "cold library script", "cold library script ÷ library", "pair ÷ cold library script",
    "import: numpy", "import: orientviz imports", "import: read", "import: write",
    "import: rest of the command",
    "solve: numpy", "solve: scipy", "solve: orientviz imports", "solve: read", "solve: block",
    "solve: adjust without precision", "solve: precision", "solve: verdict",
    "solve: rest of the command",
]  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--threads", default="1,default")
    ap.add_argument("--models", default="ladybug,axe")
    ap.add_argument("--src", default=str(SRC), help="the source tree measured (default: this one)")
    ap.add_argument("--vs-src", default=None, help="a second source tree, alternating")
    args = ap.parse_args(argv)
    trees = [args.src] + ([args.vs_src] if args.vs_src else [])
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        sys.path.insert(0, str(HERE))
        import bench_sfm  # its stripped Ladybug (orientviz from PYTHONPATH)

        bench_sfm.front_bal(str(LADYBUG), work / "front.bal")
        results: dict = {}
        for model in args.models.split(","):
            for threads in args.threads.split(","):
                dirs = {}
                for k, src in enumerate(trees):
                    d = work / f"{model}_{threads}_{k}"
                    d.mkdir()
                    (d / "front.bal").symlink_to(work / "front.bal")
                    dirs[src] = d
                    one_round(src, model, threads, d)  # warm-up: compiled modules, files
                for _ in range(args.rounds):
                    for src in trees:
                        r = derived(one_round(src, model, threads, dirs[src]))
                        results.setdefault((model, threads, src), []).append(r)
        for model in args.models.split(","):
            for threads in args.threads.split(","):
                print(f"\n{model}, threads={threads}: median of {args.rounds} (CPU s)")
                head = f"{'':34s}" + "".join(f"{Path(s).parent.name[:14]:>16s}" for s in trees)
                print(head + ("        after ÷ before" if len(trees) == 2 else ""))
                for key in ROWS:
                    vals = [
                        statistics.median(r.get(key, float("nan")) for r in results[(model, threads, s)])
                        for s in trees
                    ]  # fmt: skip
                    line = f"{key:34s}" + "".join(f"{v:16.3f}" for v in vals)
                    if len(trees) == 2 and vals[1]:
                        line += f"{vals[0] / vals[1]:16.2f}"
                    print(line)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
