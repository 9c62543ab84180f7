"""Real SfM data: orientviz's bundle against pycolmap's (Ceres) on the same model.

``python benchmarks/bench_sfm.py [--bal FILE] [--colmap DIR ...] [--skip-bal] [--skip-axe]
[--threads 1,default] [--rounds N] [--skip-cli] [--cli-rounds N] [--cli-command CMD]
[--robust LOSSES] [--dir DIR]``

Models (each measurement runs in its own fresh process: honest peak RSS):

* ``--bal`` (default: the shipped Ladybug 49-7776): the observations whose point lies
  behind its camera at the start and the points then left with fewer than two rays are
  removed first (pycolmap's reprojection cost leaves such observations out, BAL's does
  not), so both solvers minimise the same ½Σr² (px). orientviz: ``import-bal`` (f, k1,
  k2 free per camera) and the free network (minimum datum); pycolmap: one RADIAL camera
  per BAL camera (principal point held at 0), world Z reflected (BAL cameras look down
  −z), gauge TWO_CAMS_FROM_WORLD.
* the shipped COLMAP model ``axe`` (:func:`orientviz.datasets.sfm.axe_model`; unless
  ``--skip-axe``) and each ``--colmap DIR`` (a COLMAP sparse model, e.g. a SIMPLE_RADIAL
  one; the option may be repeated): orientviz ``import-colmap`` (COLMAP's objective:
  distorted pixels, focal length and distortion free, principal point held) and the
  free network; pycolmap's bundle adjuster on the model as read, the same parameters
  refined, gauge TWO_CAMS_FROM_WORLD. A point seen more than once in one image keeps its
  first keypoint in both (orientviz's import leaves the others out and counts them; the
  worker deletes them from pycolmap's reconstruction before the solve), so both
  minimise the same ½Σr² from the same start.

Per solver and thread setting: the solve's CPU and wall time (s; on a shared machine
the CPU time is the steadier number), iterations, final ½Σr² (px²), the process's peak
RSS (MB) (``--rounds N``: both solvers N times in turn, the medians of the times, the median
of the rounds' CPU ratios and their range, the largest peak RSS; "pycolmap's set-up counted": the
median of orientviz's CPU over pycolmap's set-up + solve, as orientviz's solve includes its own
set-up); "Δ½Σr²" is orientviz's final ½Σr² minus pycolmap's, relative to pycolmap's (both
stop on the same function tolerance, so on a flat optimum they stop at different points). ``1``: OPENBLAS/OMP_NUM_THREADS=1 and Ceres num_threads 1; ``default``: the
environment as a user has it and Ceres num_threads −1 (all cores). Unless
``--skip-cli``: ``orientviz import-* … && orientviz solve … --free`` end to end (CPU of
both commands, children's rusage) against orientviz's library solve measured in the
same run (``--cli-rounds N``: both N times in turn, the ratio of their medians), with
Python's compiled modules kept (PYTHONPYCACHEPREFIX in the working folder, filled by a
first run: as an installed package has them); where the environment sets
PYTHONDONTWRITEBYTECODE, also as it runs (orientviz's modules compiled at every start).
The two commands run as ``--cli-command`` (default: the ``orientviz`` console script next to
this Python, as a virtual environment puts it on PATH; ``--cli-command orientviz`` takes the
one on PATH, e.g. a pyenv shim, which adds its own start-up to each command).
Both solvers stop with Ceres's default function tolerance (1e-6 relative). pycolmap's
timed solve starts with its bundle adjuster built (the Ceres problem set up); that set-up's
CPU is printed below the table (orientviz's timed solve includes its own set-up).

``--robust huber,soft_l1,cauchy`` (instead of the table above, first thread setting
only): the stripped BAL problem with 2 % of its observations moved by 20–50 px (rng 28),
loss scale 1 px. Stage 1 solves it (``orientviz solve --free --robust L --robust-scale 1
-o``) and removes the rays that end behind their camera (pycolmap's cost leaves those
out); stage 2 is the measured problem: orientviz's robust and least-squares library
solves, pycolmap with the same loss from the start, and pycolmap started at orientviz's
robust optimum (``export-bal``): no decrease there means Ceres takes it as its optimum.
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

WORKER = r"""
import json, resource, sys, time
import numpy as np
kind, model, threads = sys.argv[1], sys.argv[2], sys.argv[3]
loss = sys.argv[4] if len(sys.argv) > 4 else "none"
out = {}
if kind == "orientviz":
    from orientviz.bundle import BundleOptions, bundle_adjust  # the solver's modules before the clock
    from orientviz.io.kinds.block import adjust_block, prepare
    from orientviz.io.problem import load_problem
    prob = load_problem(model)
    prob.options["free"] = True
    if loss != "none":
        prob.options.update(robust=loss, robust_scale=1.0)
    block, _ = prepare(prob)
    t, w = time.process_time(), time.perf_counter()
    adj, _ = adjust_block(prob, block, precision=False)
    out.update(cpu=time.process_time() - t, wall=time.perf_counter() - w,
               iterations=len(adj.history) - 1, cost=adj.history[-1].cost / 2,
               converged=bool(adj.converged))
else:
    import pycolmap
    from _pycolmap_models import (
        adjuster, bal_reconstruction, drop_repeated_observations, full_model_options)
    if kind == "pycolmap-bal":
        rec = bal_reconstruction(model)
    else:
        rec = pycolmap.Reconstruction(model)
        # a point seen twice in one image: the same rule as import-colmap (same ½Σr²)
        out["repeated_left_out"] = drop_repeated_observations(rec)
    opts = full_model_options(1 if threads == "1" else -1)
    so = opts.ceres.solver_options
    so.function_tolerance = 1e-6
    if loss != "none":
        opts.ceres.loss_function_type = getattr(pycolmap.LossFunctionType, loss.upper())
        opts.ceres.loss_function_scale = 1.0
        so.max_num_iterations = 500  # robust runs take hundreds of steps (pycolmap: 100)
    t = time.process_time()
    ba = adjuster(rec, opts)
    out["setup_cpu"] = time.process_time() - t  # the problem's set-up: not in "cpu"
    t, w = time.process_time(), time.perf_counter()
    s = ba.solve()
    cs = getattr(s, "ceres_summary", s)
    out.update(cpu=time.process_time() - t, wall=time.perf_counter() - w,
               iterations=cs.num_successful_steps + cs.num_unsuccessful_steps,
               cost=cs.final_cost, initial_cost=cs.initial_cost,
               converged="Termination: CONVERGENCE" in cs.BriefReport())
out["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps(out))
"""


#: This folder: the workers import the peer's model builders (:mod:`_pycolmap_models`) from it.
HERE = Path(__file__).resolve().parent


def _env(threads: str) -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(HERE), env.get("PYTHONPATH")) if p)
    if threads == "1":
        env.update(OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    return env


def run_worker(kind: str, model: str, threads: str, loss: str = "none") -> dict:
    res = subprocess.run(
        [sys.executable, "-c", WORKER, kind, model, threads, loss],
        capture_output=True, text=True, env=_env(threads), check=True,
    )  # fmt: skip
    return json.loads(res.stdout.strip().splitlines()[-1])


def front_bal(src: str, dst: Path) -> str:
    """``src`` without the observations behind their camera at the start and without the
    points left with fewer than two rays (see the module docstring); the counts."""
    import numpy as np

    from orientviz.io.bal import read_bal_arrays
    from orientviz.rotation import matrix_from_rotvec

    obs, cams, pts = read_bal_arrays(src)
    ci, pi = obs[:, 0].astype(int), obs[:, 1].astype(int)
    P = np.einsum("nij,nj->ni", matrix_from_rotvec(cams[:, :3])[ci], pts[pi]) + cams[ci, 3:6]
    behind = P[:, 2] >= 0
    obs = obs[~behind]
    keep = np.flatnonzero(np.bincount(obs[:, 1].astype(int), minlength=len(pts)) >= 2)
    obs = obs[np.isin(obs[:, 1].astype(int), keep)]
    new = np.full(len(pts), -1)
    new[keep] = np.arange(keep.size)
    obs[:, 1] = new[obs[:, 1].astype(int)]
    pts = pts[keep]
    with open(dst, "w") as f:
        f.write(f"{len(cams)} {len(pts)} {len(obs)}\n")
        f.writelines(f"{int(a)} {int(b)} {x!r} {y!r}\n" for a, b, x, y in obs.tolist())
        f.writelines(f"{v!r}\n" for v in np.r_[cams.ravel(), pts.ravel()].tolist())
    return f"{int(behind.sum())} observations behind their camera and {len(new) - keep.size} points removed"


def write_bal(dst: Path, obs, cams, pts) -> None:
    """A BAL text file of the arrays (observations: camera, point, x, y)."""
    import numpy as np

    with open(dst, "w") as f:
        f.write(f"{len(cams)} {len(pts)} {len(obs)}\n")
        f.writelines(f"{int(a)} {int(b)} {x!r} {y!r}\n" for a, b, x, y in obs.tolist())
        f.writelines(f"{v!r}\n" for v in np.r_[cams.ravel(), pts.ravel()].tolist())


def _without(obs, pts, drop):
    """Observations without ``drop`` (bool) and points left with fewer than two rays."""
    import numpy as np

    obs = obs[~drop]
    keep = np.flatnonzero(np.bincount(obs[:, 1].astype(int), minlength=len(pts)) >= 2)
    obs = obs[np.isin(obs[:, 1].astype(int), keep)]
    new = np.full(len(pts), -1)
    new[keep] = np.arange(keep.size)
    obs[:, 1] = new[obs[:, 1].astype(int)]
    return obs, pts[keep]


def behind(path: Path):
    """Which observations of a BAL file lie behind their camera, and the file's arrays."""
    import numpy as np

    from orientviz.io.bal import read_bal_arrays
    from orientviz.rotation import matrix_from_rotvec

    obs, cams, pts = read_bal_arrays(str(path))
    ci, pi = obs[:, 0].astype(int), obs[:, 1].astype(int)
    P = np.einsum("nij,nj->ni", matrix_from_rotvec(cams[:, :3])[ci], pts[pi]) + cams[ci, 3:6]
    return P[:, 2] > 0, (obs, cams, pts)


def robust_rows(front: Path, work: Path, losses: list[str], threads: str) -> list[dict]:
    """Robust losses on the stripped BAL problem with 2 % planted outliers (see ``--robust``)."""
    import numpy as np

    _, (obs, cams, pts) = behind(front)
    rng = np.random.default_rng(28)
    k = rng.choice(len(obs), int(round(0.02 * len(obs))), replace=False)
    ang, mag = rng.uniform(0, 2 * np.pi, k.size), rng.uniform(20, 50, k.size)
    obs[k, 2] += mag * np.cos(ang)
    obs[k, 3] += mag * np.sin(ang)
    rows = []
    for loss in losses:
        src = work / f"outliers_{loss}.bal"
        write_bal(src, obs, cams, pts)
        for stage in (1, 2):  # 2: without the rays that stage 1 left behind their camera
            js, sol, sol_bal = (
                work / f"{loss}{stage}{x}" for x in (".json", "_sol.json", "_sol.bal")
            )
            ov(["import-bal", str(src), "-o", str(js)])
            ov(["solve", str(js), "--free", "--robust", loss, "--robust-scale", "1", "-o", str(sol)],
               check=False)  # fmt: skip
            ov(["export-bal", str(sol), "-o", str(sol_bal)])
            back, (o2, c2, p2) = behind(sol_bal)
            if stage == 1:
                o_all, _, p_all = behind(src)[1]
                o_new, p_new = _without(o_all, p_all, back)
                write_bal(src, o_new, cams, p_new)
        o = run_worker("orientviz", str(js), threads, loss)
        p = run_worker("pycolmap-bal", str(src), threads, loss)
        q = run_worker("orientviz", str(js), threads)  # least squares on the same rays
        at = run_worker(
            "pycolmap-bal", str(sol_bal), threads, loss
        )  # Ceres from orientviz's optimum
        rows.append(dict(loss=loss, behind_at_optimum=int(back.sum()), orientviz=o, plain=q,
                         pycolmap=p, pycolmap_from_orientviz=at))  # fmt: skip
        print(json.dumps(rows[-1]))
    return rows


def ov(args: list[str], check: bool = True) -> None:
    subprocess.run(["orientviz", *args], check=check, capture_output=True)


def cli_end_to_end(
    import_cmd: list[str], json_path: Path, threads: str, pycache: Path | None = None,
    exe: str = "orientviz",
) -> float:  # fmt: skip
    """CPU (s) of ``orientviz import-* … && orientviz solve … --free`` (both processes).

    ``pycache``: Python keeps the compiled modules there (PYTHONPYCACHEPREFIX, one run
    before the measured one fills it) as an installed package has them; None: as the
    environment says (PYTHONDONTWRITEBYTECODE=1 compiles orientviz's modules every run).
    ``exe``: the orientviz command (a path, or a name looked up on PATH).
    """
    env = _env(threads)
    if pycache is not None:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = str(pycache)
    runs = 2 if pycache is not None else 1
    for _ in range(runs):  # the last one is measured
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run([exe, *import_cmd], check=True, capture_output=True, env=env)
        subprocess.run([exe, "solve", str(json_path), "--free"], capture_output=True, env=env)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bal", default=None, help="BAL problem (default: the shipped Ladybug)")
    ap.add_argument("--colmap", action="append", default=[],
                    help="COLMAP sparse model directory (may be repeated)")  # fmt: skip
    ap.add_argument("--skip-axe", action="store_true", help="without the shipped COLMAP model axe")
    ap.add_argument("--skip-bal", action="store_true", help="without the BAL problem")
    ap.add_argument("--threads", default="1,default")
    ap.add_argument("--rounds", type=int, default=1,
                    help="the library solves of both solvers N times in turn (medians)")  # fmt: skip
    ap.add_argument("--skip-cli", action="store_true")
    beside = Path(sys.executable).with_name("orientviz")  # what a venv puts on PATH
    ap.add_argument("--cli-command", default=str(beside) if beside.exists() else "orientviz",
                    help="the orientviz command of the CLI rows (default: the console script "
                    "next to this Python)")  # fmt: skip
    ap.add_argument("--cli-rounds", type=int, default=1,
                    help="library solve and CLI end to end measured N times in turn (medians)")  # fmt: skip
    ap.add_argument("--robust", default="", help="losses (huber,soft_l1,cauchy): see below")
    ap.add_argument("--dir", default=None, help="working folder (default: a temporary one)")
    a = ap.parse_args(argv)
    from orientviz.datasets.sfm import axe_model
    from orientviz.io.bal import shipped_bal

    work = Path(a.dir or tempfile.mkdtemp(prefix="bench_sfm_"))
    work.mkdir(parents=True, exist_ok=True)
    models = []
    bal = a.bal or str(shipped_bal())
    front = work / "front.bal"
    if not a.skip_bal or a.robust:
        print(f"BAL {bal}: {front_bal(bal, front)}")
        lb_json = work / "bal.json"
        subprocess.run(["orientviz", "import-bal", str(front), "-o", str(lb_json)], check=True,
                       capture_output=True)  # fmt: skip
        models.append(("BAL " + Path(bal).name, str(lb_json), "pycolmap-bal", str(front),
                       ["import-bal", str(front), "-o", str(lb_json)]))  # fmt: skip
    colmaps = ([] if a.skip_axe else [("axe", str(axe_model()))]) + [(d, d) for d in a.colmap]
    for k, (name, folder) in enumerate(colmaps):
        cm_json = work / f"colmap{k}.json"
        cmd = ["import-colmap", folder, "-o", str(cm_json)]
        subprocess.run(["orientviz", *cmd], check=True, capture_output=True)
        models.append(("COLMAP " + name, str(cm_json), "pycolmap", folder, cmd))
    if a.robust:
        rob = robust_rows(front, work, a.robust.split(","), a.threads.split(",")[0])
        print()
        print("| loss | orientviz it / CPU s / ½Σρ | least squares it / CPU s | pycolmap from the start "
              "it / CPU s / ½Σρ | pycolmap from orientviz's optimum it / ½Σρ start → end |")  # fmt: skip
        print("| --- | --- | --- | --- | --- |")
        for r in rob:
            o, q, p, at = r["orientviz"], r["plain"], r["pycolmap"], r["pycolmap_from_orientviz"]
            for x in (o, q, p, at):  # a run that stopped on its iteration limit: marked *
                x["iterations"] = f"{x['iterations']}{'' if x['converged'] else '*'}"
            print(f"| {r['loss']} | {o['iterations']} / {o['cpu']:.2f} / {o['cost']:.4f} | "
                  f"{q['iterations']} / {q['cpu']:.2f} | {p['iterations']} / {p['cpu']:.2f} / "
                  f"{p['cost']:.4f} | {at['iterations']} / {at['initial_cost']:.4f} → "
                  f"{at['cost']:.4f} |")  # fmt: skip
        return 0
    rows = []
    for name, ov_model, peer, peer_model, import_cmd in models:
        for threads in a.threads.split(","):
            runs = []  # the two in turn (--rounds): medians on a busy machine
            for _ in range(a.rounds):
                runs.append((run_worker("orientviz", ov_model, threads),
                             run_worker(peer, peer_model, threads)))  # fmt: skip
            o, p = _median_run([r[0] for r in runs]), _median_run([r[1] for r in runs])
            pair = [x["cpu"] / y["cpu"] for x, y in runs]
            row = dict(model=name, threads=threads, orientviz=o, pycolmap=p,
                       cpu_ratio=statistics.median(pair), rss_ratio=o["peak_rss_mb"] / p["peak_rss_mb"])  # fmt: skip
            if "setup_cpu" in p:  # both set-ups counted (orientviz's is inside its solve)
                with_setup = [x["cpu"] / (y["cpu"] + y["setup_cpu"]) for x, y in runs]
                row["cpu_ratio_with_setup"] = statistics.median(with_setup)
            if a.rounds > 1:
                row["cpu_ratios"] = pair
            if not a.skip_cli:
                lib = [o["cpu"]]
                exe = a.cli_command
                cli = [cli_end_to_end(import_cmd, Path(ov_model), threads, work / "pyc", exe)]
                for _ in range(a.cli_rounds - 1):  # the two in turn: medians on a busy machine
                    lib.append(run_worker("orientviz", ov_model, threads)["cpu"])
                    cli.append(
                        cli_end_to_end(import_cmd, Path(ov_model), threads, work / "pyc", exe)
                    )
                row["cli_cpu"], row["cli_lib_cpu"] = statistics.median(cli), statistics.median(lib)
                row["cli_ratio"] = row["cli_cpu"] / row["cli_lib_cpu"]
                row["cli_rounds"] = dict(library=lib, cli=cli)
                if os.environ.get("PYTHONDONTWRITEBYTECODE"):  # and as this environment runs it
                    row["cli_cpu_compiling"] = cli_end_to_end(
                        import_cmd, Path(ov_model), threads, exe=exe
                    )
            rows.append(row)
            print(json.dumps(row))
    print()
    print("| model | threads | orientviz it / CPU s / ½Σr² / peak MB | pycolmap it / CPU s / ½Σr² / peak MB "
          "| Δ½Σr² | CPU ratio | CPU ratio, pycolmap's set-up counted | memory ratio "
          "| CLI end to end CPU s (÷ library solve) |")  # fmt: skip
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in rows:
        o, p = r["orientviz"], r["pycolmap"]
        cli = f"{r['cli_cpu']:.2f} ({r['cli_ratio']:.2f}×)" if "cli_cpu" in r else "—"
        if "cli_cpu" in r and a.cli_rounds > 1:
            cli += f", medians of {a.cli_rounds} (library {r['cli_lib_cpu']:.2f})"
        if "cli_cpu_compiling" in r:
            c = r["cli_cpu_compiling"]
            cli += f"; compiling: {c:.2f} ({c / r.get('cli_lib_cpu', o['cpu']):.2f}×)"
        ratio = f"{r['cpu_ratio']:.2f}"
        if "cpu_ratios" in r:
            ratio += f" ({min(r['cpu_ratios']):.2f}–{max(r['cpu_ratios']):.2f})"
        setup = f"{r['cpu_ratio_with_setup']:.2f}" if "cpu_ratio_with_setup" in r else "—"
        print(f"| {r['model']} | {r['threads']} | {o['iterations']} / {o['cpu']:.3f} / {o['cost']:.3f} / "
              f"{o['peak_rss_mb']:.0f} | {p['iterations']} / {p['cpu']:.3f} / {p['cost']:.3f} / "
              f"{p['peak_rss_mb']:.0f} | {(o['cost'] - p['cost']) / p['cost']:+.1e} | "
              f"{ratio} | {setup} | {r['rss_ratio']:.2f} | {cli} |")  # fmt: skip
    if a.rounds > 1:
        print(f"\nCPU: medians of {a.rounds} rounds (the two solvers in turn); CPU ratio: the median "
              "of the rounds' ratios (range); peak MB: the largest.")  # fmt: skip
    print("pycolmap's problem set-up (its bundle adjuster built, before its timed solve; "
          "orientviz's solve includes its own), CPU s: "
          + ", ".join(f"{r['model']} ({r['threads']}) {r['pycolmap'].get('setup_cpu', float('nan')):.3f}"
                      for r in rows))  # fmt: skip
    return 0


def _median_run(runs: list[dict]) -> dict:
    """One solver's runs as one: the first run's iterations and ½Σr², the medians of the
    times, the largest peak RSS."""
    out = dict(runs[0])
    for k in ("cpu", "wall", "setup_cpu"):
        if k in out:
            out[k] = statistics.median(r[k] for r in runs)
    out["peak_rss_mb"] = max(r["peak_rss_mb"] for r in runs)
    return out


if __name__ == "__main__":
    raise SystemExit(main())
