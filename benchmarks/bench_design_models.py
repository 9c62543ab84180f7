"""The independent-models design of the 1 000-image block: its base blocks and the whole design.

CPU medians (one BLAS thread) of 5 runs of ``LiveModels._base_blocks`` (selected inverse and
the point blocks) and of a new :class:`orientviz.design.LiveModels`, printed with the path of
the orientviz it ran, for A/B runs in turn with another checkout::

    for i in 1 2 3; do
        PYTHONPATH=/work/wt/studio/src python benchmarks/bench_design_models.py
        PYTHONPATH=/work/main/src python benchmarks/bench_design_models.py
    done
"""

from __future__ import annotations

import time

import numpy as np
from threadpoolctl import threadpool_limits

import orientviz
from orientviz.design import FlightDesign, LiveModels, design_block


def main() -> None:
    b, spec = design_block(FlightDesign(strips=20, images_per_strip=50))
    with threadpool_limits(1, "blas"):
        lm = LiveModels(b, spec)
        tb, td = [], []
        for _ in range(5):
            t = time.process_time()
            lm._base_blocks()
            tb.append(time.process_time() - t)
            t = time.process_time()
            LiveModels(b, spec)
            td.append(time.process_time() - t)
    print(
        f"{orientviz.__file__}: base blocks {1e3 * np.median(tb):.0f} ms, "
        f"design {1e3 * np.median(td):.0f} ms (CPU medians of 5)"
    )


if __name__ == "__main__":
    main()
