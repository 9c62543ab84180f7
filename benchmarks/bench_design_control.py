"""Control changes of the 1 000-image design, bundle and independent models: CPU per change.

A quick A/B of one code change against another checkout: the same script run in turn
with two ``PYTHONPATH`` settings prints the median CPU time (one BLAS thread) of
``--changes`` control points added one after another, by
:class:`orientviz.design.LiveDesign` (bundle) and :class:`orientviz.design.LiveModels`
(independent models), and which checkout it ran::

    for i in 1 2 3; do
        PYTHONPATH=/work/wt/studio/src python benchmarks/bench_design_control.py
        PYTHONPATH=/work/main/src python benchmarks/bench_design_control.py
    done

The full table of every change is ``bench_design.py``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from threadpoolctl import threadpool_limits

import orientviz
from orientviz.block import CONTROL
from orientviz.design import FlightDesign, LiveDesign, LiveModels, design_block


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--strips", type=int, default=20)
    ap.add_argument("--images", type=int, default=50)
    ap.add_argument("--changes", type=int, default=12)
    args = ap.parse_args()
    b, spec = design_block(FlightDesign(strips=args.strips, images_per_strip=args.images))
    tie = np.flatnonzero(b.points.role == 0)
    picks = tie[:: max(1, tie.size // args.changes)][: args.changes]
    with threadpool_limits(1, "blas"):
        live = LiveDesign(b, spec)
        tb = []
        for j in picks:
            t = time.process_time()
            live.add_control(int(j), 0.02)
            tb.append(time.process_time() - t)
        mb = b.copy()
        models = LiveModels(mb, spec)
        tm = []
        for j in picks:
            P = mb.points
            P.sigma[j], P.xyz_known[j], P.role[j] = 0.02, P.xyz[j], CONTROL
            t = time.process_time()
            models.sync()
            tm.append(time.process_time() - t)
    print(
        f"{orientviz.__file__}: control added, bundle {1e3 * np.median(tb):.1f} ms, "
        f"models {1e3 * np.median(tm):.1f} ms (CPU medians of {picks.size})"
    )


if __name__ == "__main__":
    main()
