"""Self-calibrating bundle against the plain bundle on the same block, in one run.

    python benchmarks/bench_selfcal.py                  # large (2 100 images), 3 reps
    python benchmarks/bench_selfcal.py --sizes medium,large --reps 5 --set ebner12

Issue 5's target: the bundle of the bench's 2 100-image block (30 strips × 70 images)
with 12 additional parameters per strip (Ebner's set, ``ap_group`` = strip, q = 360,
pseudo-observations 0 ± 10 µm) in at most 1.5× the time of the plain bundle. Both
runs time ``bundle_adjust(precision=False)`` on the same Block in the same process,
alternating plain / self-calibrating per repetition so that a change of machine load
hits both; ``ratio`` = best self-cal / best plain (also the ratio of the medians; ``ratio_cpu`` the same with CPU time). BLAS
threads are pinned to 1 (``--threads``), as in ``bench_bundle.py``. The block comes from
the shared bench (``make_block.py``, see ``bench_bundle.py``); its image errors are random
only, so the parameters stay near 0 — the cost of the algebra is what is measured.

``--precision`` adds a second table: the same two runs with ``precision=True`` (cofactor
blocks, redundancy numbers; :mod:`orientviz.bundle.precision._precision`), timed in the same
repetitions. ``prec_ratio`` = self-cal with precision / plain with precision (best);
``prec_extra`` = what the precision adds to the self-calibrating bundle, in units of the
plain bundle without precision: (best self-cal with − best self-cal without) / best plain
without. Issue 5's target for it is about 1.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--sizes", default="large")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--set", default="ebner12", help="additional-parameter set")
    ap.add_argument("--threads", type=int, default=1, help="BLAS threads")
    ap.add_argument(
        "--precision", action="store_true", help="also time precision=True (plain and self-cal)"
    )
    a = ap.parse_args(argv)
    for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[k] = str(a.threads)  # before numpy is imported
    sys.path.insert(0, str(HERE))
    sys.path.insert(0, str(HERE.parent / "src"))
    from bench_blocks import load_bench_block
    from bench_bundle import ensure_data

    from orientviz.bundle import ap_set, bundle_adjust

    print(f"# {time.strftime('%Y-%m-%d %H:%M:%S')}  load average {os.getloadavg()}")
    head = (
        f"{'size':7s} {'images':>6s} {'q':>4s} {'plain_s':>8s} {'selfcal_s':>9s} "
        f"{'ratio':>6s} {'ratio_med':>9s} {'ratio_cpu':>9s} {'it_plain':>8s} {'it_sc':>5s} {'sigma0_sc':>9s}"
    )
    print(head + "\n" + "-" * len(head))
    aps = ap_set(a.set)
    rows_prec = []
    for size in a.sizes.split(","):
        block, _ = load_bench_block(ensure_data(size))
        kw_sc = dict(additional=aps, ap_group=block.images.strip, ap_sigma=10.0)
        runs = [("plain", False, {}), ("sc", False, kw_sc)]
        if a.precision:
            runs += [("plain", True, {}), ("sc", True, kw_sc)]
        wall = {(name, p): [] for name, p, _ in runs}
        cpu = {(name, p): [] for name, p, _ in runs}
        res = {}
        for _ in range(a.reps):  # alternating, so that a change of load hits all runs
            for name, prec, kw in runs:
                t0, c0 = time.perf_counter(), time.process_time()
                res[name, prec] = bundle_adjust(block, precision=prec, **kw)
                wall[name, prec].append(time.perf_counter() - t0)
                cpu[name, prec].append(time.process_time() - c0)
        tp, ts = wall["plain", False], wall["sc", False]
        cp, cs = cpu["plain", False], cpu["sc", False]
        rp, rs = res["plain", False], res["sc", False]
        q = rs.groups["additional"].stop - rs.groups["additional"].start
        print(
            f"{size:7s} {block.n_images:6d} {q:4d} {min(tp):8.3f} {min(ts):9.3f} "
            f"{min(ts) / min(tp):6.2f} {statistics.median(ts) / statistics.median(tp):9.2f} "
            f"{min(cs) / min(cp):9.2f} "
            f"{rp.iterations:8d} {rs.iterations:5d} {rs.sigma0:9.4f}",
            flush=True,
        )
        if a.precision:
            pp, ps = wall["plain", True], wall["sc", True]
            extra = [(b - c) / min(tp) for b, c in zip(ps, ts)]  # per repetition
            rows_prec.append(
                f"{size:7s} {min(pp):8.3f} {min(ps):9.3f} {min(ps) / min(pp):10.2f} "
                f"{statistics.median(ps) / statistics.median(pp):14.2f} "
                f"{(min(ps) - min(ts)) / min(tp):10.2f} {statistics.median(extra):15.2f}"
            )
    if rows_prec:
        head = (
            f"{'size':7s} {'plain_ps':>8s} {'selfcal_ps':>9s} {'prec_ratio':>10s} "
            f"{'prec_ratio_med':>14s} {'prec_extra':>10s} {'prec_extra_med':>15s}"
        )
        print("\nwith precision=True (same repetitions)\n" + head + "\n" + "-" * len(head))
        print("\n".join(rows_prec))
    print(f"# load average now {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
