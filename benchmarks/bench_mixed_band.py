"""Single-precision band factor with refined solves (``bundle/_mixed_band.py``) on/off.

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_mixed_band.py --sizes large --reps 8

Adjusts each bench block (``bundle_adjust(precision=False)``, in this process)
alternately with the mixed-precision factor (as shipped) and with every factor in
double precision (``MIN_BAND_FLOPS = inf``), so both see the same load. Prints CPU time
(``time.process_time``) best and median, iterations, σ0 of both, the largest
difference of the two solutions (m) and the refinement rounds of each solve (−1: fell
back to double precision). The blocks come from the peer bench (``bench_bundle.py``
makes them in $ORIENTVIZ_BENCH_DATA or /tmp/orientviz-bench).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "src"))  # this checkout's orientviz


def run(size: str, reps: int) -> str:
    from bench_blocks import load_bench_block
    from bench_bundle import ensure_data

    import orientviz.bundle._problem as problem
    import orientviz.bundle._reduced as reduced
    from orientviz.bundle import bundle_adjust

    block, _ = load_bench_block(str(ensure_data(size)), control="fixed")
    shipped = reduced.MIN_BAND_FLOPS
    factors: list = []
    original = reduced.factor_reduced

    def spy(*args, **kw):
        fac = original(*args, **kw)
        factors.append(fac)
        return fac

    problem.factor_reduced = spy
    cpu: dict[bool, list[float]] = {True: [], False: []}
    res = {}
    try:
        for _ in range(reps):
            for mixed in (True, False):
                reduced.MIN_BAND_FLOPS = shipped if mixed else np.inf
                factors.clear()
                t0 = time.process_time()
                res[mixed] = bundle_adjust(block, control="fixed", precision=False)
                cpu[mixed].append(time.process_time() - t0)
                if mixed:
                    rounds = [getattr(f.data, "rounds", f.kind) for f in factors]
    finally:
        reduced.MIN_BAND_FLOPS = shipped
        problem.factor_reduced = original
    a, b = res[True], res[False]
    return (
        f"| {size} | {min(cpu[True]):.3f} | {statistics.median(cpu[True]):.3f} | "
        f"{min(cpu[False]):.3f} | {statistics.median(cpu[False]):.3f} | "
        f"{min(cpu[True]) / min(cpu[False]):.2f} | {a.iterations} / {b.iterations} | "
        f"{a.sigma0:.7f} / {b.sigma0:.7f} | {np.max(np.abs(a.x - b.x)):.1e} | {rounds} |"
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="medium,large")
    ap.add_argument("--reps", type=int, default=5)
    args = ap.parse_args(argv)
    print(
        "| block | mixed CPU s | median | double CPU s | median | ratio | iterations | σ0 "
        "| max Δx | refinement rounds per factor |"
    )
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for size in args.sizes.split(","):
        print(run(size, args.reps), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
