"""The bundle's CPU time split into the reduced system's part and everything else.

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_bundle_parts.py
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_bundle_parts.py --sizes medium,large \\
        --against /path/to/old/checkout/src --rounds 3

The timed path is ``bench_bundle.py``'s: ``Block.from_arrays`` from the bench block's
in-memory arrays and ``bundle_adjust(precision=False)``. Its CPU time
(``time.process_time``) is split into the *reduced system* — forming S from the tracks
(``schur_blocks``), factoring it (``factor_reduced``), solving with the factor
(``Factor.solve``) and choosing the solver (``ReducedStructure._setup_solver``) — and
*the rest*: the block's construction, the set-up of the problem, the evaluations
(projections and Jacobians), the normal equations without S (point products, image
blocks, right-hand sides), back-substitution, apply, cost and the result. Each checkout
runs in its own process (this one's ``src`` and every ``--against``), alternately for
``--rounds`` rounds; the table shows the best of all repetitions per column, so that an
old checkout is compared in the same minutes.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def worker(src: str, size: str, reps: int) -> dict:
    """Time the path ``reps`` times with the code of ``src``; best totals and splits."""
    sys.path.insert(0, src)
    sys.path.insert(0, str(HERE))
    from bench_blocks import load_bench_block, npz_path, user_arrays

    from orientviz.block import Block
    from orientviz.bundle import bundle_adjust
    from orientviz.bundle.problem import _problem
    from orientviz.bundle.reduced import Factor, ReducedStructure

    block, _ = load_bench_block(npz_path(size), control="fixed")
    arrays = user_arrays(block)
    spent = [0.0]

    def timed(owner, name: str) -> None:
        f = getattr(owner, name, None)
        if f is None:
            return

        def g(*args, **kwargs):
            t = time.process_time()
            try:
                return f(*args, **kwargs)
            finally:
                spent[0] += time.process_time() - t

        setattr(owner, name, g)

    timed(_problem, "schur_blocks")
    timed(_problem, "factor_reduced")
    timed(Factor, "solve")
    timed(ReducedStructure, "_setup_solver")
    totals, reduced = [], []
    for _ in range(reps):
        spent[0] = 0.0
        t = time.process_time()
        res = bundle_adjust(Block.from_arrays(**arrays), control="fixed", precision=False)
        totals.append(time.process_time() - t)
        reduced.append(spent[0])
    rest = [a - b for a, b in zip(totals, reduced)]
    return dict(total=min(totals), reduced=min(reduced), rest=min(rest), iters=res.iterations,
                sigma0=res.sigma0)  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="large", help="bench blocks, comma-separated")
    ap.add_argument("--against", action="append", default=[], help="another checkout's src")
    ap.add_argument("--reps", type=int, default=4, help="repetitions per process")
    ap.add_argument("--rounds", type=int, default=3, help="processes per checkout")
    ap.add_argument("--worker", nargs=3, metavar=("SRC", "SIZE", "REPS"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        src, size, reps = args.worker
        print("@@RESULT " + json.dumps(worker(src, size, int(reps))))
        return
    srcs = [str(HERE.parent / "src")] + [str(Path(s).resolve()) for s in args.against]
    print(f"# {time.strftime('%Y-%m-%d %H:%M:%S')}  load average {os.getloadavg()}")
    print(
        f"{'size':7} {'iters':>5} {'sigma0':>9} {'total ms':>9} {'reduced ms':>10} {'rest ms':>8}  src"
    )
    for size in args.sizes.split(","):
        best: dict[str, dict] = {}
        for _ in range(args.rounds):
            for src in srcs:
                cmd = [sys.executable, __file__, "--worker", src, size, str(args.reps)]
                out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
                r = json.loads(out.split("@@RESULT ", 1)[1])
                b = best.setdefault(src, r)
                for k in ("total", "reduced", "rest"):
                    b[k] = min(b[k], r[k])
        for src in srcs:
            b = best[src]
            print(
                f"{size:7} {b['iters']:5d} {b['sigma0']:9.5f} {1e3 * b['total']:9.1f} "
                f"{1e3 * b['reduced']:10.1f} {1e3 * b['rest']:8.1f}  {src}"
            )
    print(f"# load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
