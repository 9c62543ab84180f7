"""Robust ÷ least-squares CPU of the library solve on DBAT blocks with planted gross errors.

Issue 28 point 3 asks a robust run (Huber, soft-L1, Cauchy inside the Levenberg–Marquardt
loop) for at most twice the CPU of the plain solve. Per block (``--blocks``: shipped DBAT
problems, 2 % of their rays moved by 20–50 σ as ``tests/planted_outliers.py`` does, rng 28,
the loss's default scale) a fresh process per source tree solves least squares and each
loss in turn ``--reps`` times (``adjust_block(precision=False)``, the clock around the
adjustment only) and prints the medians; the trees (``--src``, default this checkout's
``src``) alternate round by round, so a before/after is measured in the same rounds.
Printed per round: the ratio of the medians, the steps and ½Σρ of the last run (a tree
that changes a robust path shows it there). Quote the rows with ``uptime``'s load.

Usage::

    python benchmarks/bench_robust.py --rounds 5 --reps 9 --threads 1 \\
        --src /path/to/before/src --src src
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

#: What a worker process runs: its tree's orientviz on the planted block.
WORKER = r"""
import copy, json, statistics, sys, time
sys.path.insert(0, sys.argv[1])
from planted_outliers import planted_dbat
from orientviz.io.kinds.block import adjust_block

name, losses, reps = sys.argv[2], sys.argv[3].split(","), int(sys.argv[4])
prob, block = planted_dbat(name)


def run(loss):
    p = copy.deepcopy(prob)
    p.options.update(robust=loss)
    b = copy.deepcopy(block)
    t = time.process_time()
    adj, _ = adjust_block(p, b, precision=False)
    return time.process_time() - t, adj


kinds = ["none"] + losses
for k in kinds:  # imports, caches: not measured
    run(k)
cpu = {k: [] for k in kinds}
last = {}
for _ in range(reps):
    for k in kinds:
        dt, last[k] = run(k)
        cpu[k].append(dt)
out = {}
for k in kinds:
    h = last[k].history
    out[k] = dict(cpu=statistics.median(cpu[k]), steps=len(h) - 1, half_rho=h[-1].cost / 2,
                  converged=bool(last[k].converged))
print(json.dumps(out))
"""


def worker(src: str, block: str, losses: list[str], reps: int, threads: str) -> dict:
    """The medians of one fresh process of tree ``src`` (see :data:`WORKER`)."""
    env = dict(os.environ, PYTHONPATH=src)
    if threads == "1":
        env.update(OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    else:
        for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
            env.pop(k, None)
    args = [sys.executable, "-c", WORKER, str(HERE.parent / "tests"), block, ",".join(losses)]
    res = subprocess.run(args + [str(reps)], env=env, capture_output=True, text=True, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def load() -> str:
    """The 1-minute load average."""
    return Path("/proc/loadavg").read_text().split()[0] if Path("/proc/loadavg").exists() else "?"


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--src", action="append", default=[], help="a source tree (repeat)")
    ap.add_argument("--blocks", default="dbat_sxb,dbat_camcal")
    ap.add_argument("--losses", default="huber,soft_l1,cauchy")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--reps", type=int, default=9)
    ap.add_argument("--threads", default="1", choices=["1", "default"])
    a = ap.parse_args(argv)
    trees = a.src or [str(HERE.parent / "src")]
    losses = a.losses.split(",")
    ratios: dict = {}
    for block in a.blocks.split(","):
        for r in range(1, a.rounds + 1):
            for src in trees:
                at = load()
                res = worker(src, block, losses, a.reps, a.threads)
                ls = res["none"]["cpu"]
                for k in losses:
                    x = res[k]
                    ratios.setdefault((block, k, src), []).append(x["cpu"] / ls)
                    print(
                        f"{block} {k} round {r} {src} (load {at}): {x['cpu'] / ls:.3f} "
                        f"({x['cpu'] * 1e3:.1f} / {ls * 1e3:.1f} ms), {x['steps']} steps, "
                        f"½Σρ {x['half_rho']:.9f}{'' if x['converged'] else ' NOT CONVERGED'}",
                        flush=True,
                    )
    print("\n| block, loss | " + " | ".join(trees) + " |")
    print("| --- |" + " --- |" * len(trees))
    for block in a.blocks.split(","):
        for k in losses:
            cells = []
            for src in trees:
                v = ratios[(block, k, src)]
                cells.append(f"{statistics.median(v):.3f} ({min(v):.3f}–{max(v):.3f})")
            print(f"| {block} {k}, {a.threads} thread(s) | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
