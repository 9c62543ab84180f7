"""Chord steps of the bundle (``BundleOptions.chord_reuse``): iterations, factorisations and CPU time.

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_chord.py               # all blocks
    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_chord.py --blocks large --reps 5

Each block is adjusted (``precision=False``, in this process) with the chord steps as
they are and with every step a Newton step (``BundleOptions(chord_reuse=0)``), in the same run: the
number of iterations, of factorisations of the reduced system S (full steps), σ0, the
largest difference of the two solutions' tie points (mm) and the CPU time
(``time.process_time``, best of ``--reps``).
``--src`` runs another checkout's code (its ``src`` folder; the script needs only
``bundle_adjust`` and ``BundleProblem.solve``'s ``fac`` argument) to compare with it.

Blocks: the peer bench's aerial strips (``small``, ``medium``, ``large``: 24, 200 and
2 100 images, ``make_block.py`` data in $ORIENTVIZ_BENCH_DATA or /tmp/orientviz-bench;
``benchmarks/bench_bundle.py`` makes them), the same with the observations' σ 40 times
too small (``*-sigma40``: σ0 ≈ 40 at the optimum, the steps in rotations of the image
frames last longer), and a close-range ring of 16 images from a start 0.5 m / 0.05 rad
off (``ring``, the tests' network).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests" / "bundle"))


def make_block(name: str):
    """The block ``name`` (see the module docstring)."""
    if name == "ring":
        from unordered_networks import close_range_network

        return close_range_network(m=16, p=150, start_error=0.5)[0]
    from bench_blocks import load_bench_block, npz_path

    size, _, variant = name.partition("-")
    path = npz_path(size)
    if not path.exists():
        raise SystemExit(f"{path} missing: run benchmarks/bench_bundle.py --sizes {size} first")
    block, _ = load_bench_block(path, control="fixed")
    if variant == "sigma40":
        block.observations.sigma[:] = block.observations.sigma / 40.0
    return block


def run(block, reps: int, newton: bool) -> dict:
    from orientviz.bundle import BundleOptions, bundle_adjust
    from orientviz.bundle.problem import _problem

    full = []
    solve = _problem.BundleProblem.solve

    def counting(self, ne, names, fac=None):
        full.append(fac is None)
        return solve(self, ne, names, fac=fac)

    opts = BundleOptions(chord_reuse=0.0) if newton else BundleOptions()
    _problem.BundleProblem.solve = counting
    try:
        cpus = []
        for _ in range(reps):
            full.clear()
            c0 = time.process_time()
            res = bundle_adjust(block, precision=False, options=opts)
            cpus.append(time.process_time() - c0)
    finally:
        _problem.BundleProblem.solve = solve
    return dict(res=res, cpu=min(cpus), factors=sum(full), iters=res.iterations)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--blocks", default="small,medium,large,medium-sigma40,large-sigma40,ring")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--src", default=str(HERE.parent / "src"), help="orientviz's src folder")
    a = ap.parse_args()
    sys.path.insert(0, a.src)
    import orientviz

    print(
        f"# load average {os.getloadavg()[0]:.1f}, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}"
        f", OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}"
        f", {Path(orientviz.__file__).parent.parent}"
    )
    print(
        "| block | iters | factors | CPU s | iters Newton | factors Newton | CPU s Newton "
        "| σ0 | max Δ tie point mm |"
    )
    print("|" + " --- |" * 9)
    from orientviz.block import TIE

    for name in a.blocks.split(","):
        block = make_block(name)
        chord = run(block, a.reps, newton=False)
        newton = run(block, a.reps, newton=True)
        tie = block.points.role == TIE
        d = chord["res"].points[tie] - newton["res"].points[tie]
        print(
            f"| {name} | {chord['iters']} | {chord['factors']} | {chord['cpu']:.3f} "
            f"| {newton['iters']} | {newton['factors']} | {newton['cpu']:.3f} "
            f"| {chord['res'].sigma0:.5f} | {1000 * np.abs(d).max():.1e} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
