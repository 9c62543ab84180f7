"""Detection bound from test power: what any test at the cleaning's level could find.

Run:  python benchmarks/bench_gross_bound.py [grid|gruber] [number of seeds]

For the blocks of :mod:`bench_gross` (same simulation, same seeds) each error ≥ 6 σ gets
the power of the exact 2-D test of the *error-free* block against it alone,
1 − F(χ²_crit; dof, λ) with λ its non-centrality and the B-method critical value of the
ray's rank (α0 = 0.1 %, β0 = 80 %). The mean over the errors is the detection one would
expect from a test that sees each error in isolation. Where the cleaning stays below it,
the loss is identification (which ray of a point is wrong) and interaction between
errors, not the power of the test.
"""

from __future__ import annotations

import os
import sys

for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import bench_gross as bg  # noqa: E402
import numpy as np  # noqa: E402
from scipy.stats import ncx2  # noqa: E402

from orientviz.adjust.gross2d import critical_values_2d, statistic_2d  # noqa: E402
from orientviz.bundle import bundle_solver  # noqa: E402  (after the sys.path insert)


def main() -> None:
    tie = sys.argv[1] if len(sys.argv) > 1 else "gruber"
    seeds = range(1, (int(sys.argv[2]) if len(sys.argv) > 2 else 24) + 1)
    crit = critical_values_2d(0.001, 0.80)
    power, skipped = [], []
    for seed in seeds:
        clean, dirty = bg.make(seed, 4, 10, tie)
        try:
            info = bg.truth_info(clean, dirty)
        except Exception:  # the error-free bundle fails (weak geometry), as in bench_gross
            skipped.append(seed)
            continue
        n = dirty.block.n_observations
        ref = bundle_solver(clean.block)(np.ones(2 * n))
        r = np.nan_to_num(ref.redundancy_numbers.reshape(n, 2)[info["idx"]])
        rxy = np.nan_to_num(ref.redundancy_xy[info["idx"]])
        _, dof = statistic_2d(np.zeros_like(r), r, rxy)
        for size, lam, d in zip(info["size"], info["lam"], dof):
            if size >= 6:
                d = int(d)
                power.append(0.0 if d == 0 else 1.0 - ncx2.cdf(crit[d], d, lam))
    p = np.array(power)
    print(f"tie {tie!r}, seeds {list(seeds)} (skipped {skipped}): {p.size} errors ≥ 6 σ, "
          f"expected detection from the power of each error alone {p.mean():.1%}, "
          f"{(p < 0.8).sum()} of them with power below 80 %")  # fmt: skip


if __name__ == "__main__":
    main()
