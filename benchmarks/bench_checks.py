"""Cost of the plausibility checks against the solve they guard, on the bench blocks.

    python benchmarks/bench_checks.py                    # small, medium
    python benchmarks/bench_checks.py --sizes small,medium,large --repeat 5

For each block of the shared bench (``make_block.py``, data in $ORIENTVIZ_BENCH_DATA,
default /tmp/orientviz-bench): the best of ``--repeat`` runs of
:func:`orientviz.plausibility.check_block` (image coordinates outside the format, points
far away, points behind cameras, observations per image, intersection angles), and of
the solve ``orientviz solve`` runs (``bundle_adjust`` with precision, the default) in the
same process, and their ratio in percent. Issue #19 asks for < 5 %.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "src"))  # this checkout's orientviz


def best(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="small,medium")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()

    from bench_blocks import load_bench_block
    from bench_bundle import ensure_data

    from orientviz.bundle import bundle_adjust
    from orientviz.plausibility import check_block

    print(f"{'block':8s} {'images':>6s} {'rays':>8s} {'checks ms':>10s} {'solve ms':>10s} "
          f"{'checks/solve':>12s}  findings")  # fmt: skip
    for size in args.sizes.split(","):
        block, _ = load_bench_block(ensure_data(size))
        findings = check_block(block)
        t_check = best(lambda b=block: check_block(b), max(args.repeat, 5))
        t_solve = best(lambda b=block: bundle_adjust(b, control="fixed"), args.repeat)
        print(
            f"{size:8s} {block.n_images:6d} {block.n_observations:8d} {t_check * 1e3:10.2f} "
            f"{t_solve * 1e3:10.1f} {100 * t_check / t_solve:11.2f} %  "
            f"{[f.check for f in findings] or 'none'}"
        )


if __name__ == "__main__":
    main()
