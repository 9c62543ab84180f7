"""One change of a block design: the low-rank update against a new assessment.

A design block of ``--strips`` × ``--images`` images (default 20 × 50 = 1 000, standard
points, perimeter control every 4 bases, σ 5 µm, control σ 2 cm) is assessed once
(:class:`orientviz.design.LiveDesign`: the bundle's precision and reliability, its
factorised normal equations). Then ``--changes`` times a tie point is made control (or a
change is undone), timed as the studio runs it: the update of σ of all points and
stations, redundancy numbers, MDB, external reliability, ellipsoids, weak spots and summary
(``LiveDesign.set_control`` / ``undo``); then the suggestion of the next control point
(``suggest_control``, 40 candidates). The peer in the same run: a new
:func:`orientviz.design.assess_block` of the changed design (forming and factoring again).

    python benchmarks/bench_design.py                 # 1 000 images
    python benchmarks/bench_design.py --strips 4 --images 10
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from orientviz.design import (
    FlightDesign,
    LiveDesign,
    assess_block,
    design_block,
    suggest_control,
)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--strips", type=int, default=20)
    ap.add_argument("--images", type=int, default=50)
    ap.add_argument("--changes", type=int, default=8)
    args = ap.parse_args()
    print(f"load average {os.getloadavg()}, threads: default BLAS")
    t = time.perf_counter()
    block, spec = design_block(FlightDesign(strips=args.strips, images_per_strip=args.images))
    print(
        f"design block {block.n_images} images, {block.n_points} points, "
        f"{block.n_observations} rays: {time.perf_counter() - t:.2f} s"
    )
    t = time.perf_counter()
    live = LiveDesign(block, spec)
    print(f"base assessment + factorisation: {time.perf_counter() - t:.2f} s")
    tie = np.flatnonzero(block.points.role == 0)
    rng = np.random.default_rng(1)
    picks = rng.choice(tie, size=args.changes, replace=False)
    times, adds = [], []
    for k, j in enumerate(picks):
        t = time.perf_counter()
        if k % 4 == 3:
            q = live.undo()
            what = "undo"
        else:
            q = live.add_control(int(j), 0.02)
            what = f"add control at {block.points.ids[j]}"
        dt = time.perf_counter() - t
        times.append(dt)
        if what != "undo":
            adds.append(dt)
        s = q.summary
        print(
            f"  change {k + 1} ({what}, {len(live.changes)} changed points): {dt * 1e3:.0f} ms;"
            f" σ_Z max {s['sigma_z_max'] * 1e3:.1f} mm"
        )
    t = time.perf_counter()
    sug = suggest_control(live, criterion="sigma_z")
    print(
        f"suggestion ({sug.candidates.size} candidates): {time.perf_counter() - t:.2f} s; {sug.describe()}"
    )
    t = time.perf_counter()
    assess_block(live.block, spec)
    full = time.perf_counter() - t
    med = float(np.median(adds))
    print(
        f"added control: median {med * 1e3:.0f} ms, max {max(adds) * 1e3:.0f} ms "
        f"(all changes with undo: median {np.median(times) * 1e3:.0f} ms); "
        f"new assessment of the same design {full:.2f} s ({full / med:.0f} × the added median)"
    )


if __name__ == "__main__":
    main()
