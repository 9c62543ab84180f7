"""Problem files: write and load time of orientviz/1 JSON against plain json and numpy.

    python benchmarks/bench_problem_files.py                 # 4x10 and 10x20 image blocks
    python benchmarks/bench_problem_files.py --sizes 20x50   # ~60 000 observations

For each simulated block (orientviz.simulate, seed 3) and each table form
(readable rows / compact columns) the table lists, best of ``--repeat`` runs in this
process (imports warmed up first):

* ``write`` — ``dumps_problem`` (unit conversion, 15-digit numbers, schema validation of
  the written document, pretty printing);
* ``load`` — ``loads_problem`` (strict parse, NaN/duplicate-key scan, schema validation
  with the array reduction of ``io/reduce.py``, id checks, unit conversion, Block);
* peers in the same run: ``json.loads`` of the same text (no checks at all) and
  ``np.load`` of the same tables saved as ``.npz`` (binary, no ids checked);
* ``full-val`` — jsonschema on the *unreduced* document, i.e. what validation alone
  would cost without the reduction (only for blocks up to 20 000 observations).
"""

from __future__ import annotations

import argparse
import io
import json
import time

import numpy as np

from orientviz.io.jsonio import validator_for
from orientviz.io.problem import dumps_problem, loads_problem, problem_from_block
from orientviz.simulate import simulate_block


def best(repeat: int, func, *args, **kwargs) -> float:
    """Shortest wall time of ``func(*args, **kwargs)`` over ``repeat`` runs, in s."""
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        func(*args, **kwargs)
        times.append(time.perf_counter() - t)
    return min(times)


def npz_bytes(block) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, X0=block.images.X0, angles=block.images.angles, xyz=block.points.xyz,
             oi=block.observations.image, op=block.observations.point,
             xy=block.observations.xy, sigma=block.observations.sigma)  # fmt: skip
    return buf.getvalue()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default="4x10,10x20", help="strips x images, comma separated")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    validator_for("block.json")  # warm up imports
    header = (f"{'block':>8s} {'obs':>7s} {'form':>9s} {'MB':>6s} {'write s':>8s} "
              f"{'load s':>8s} {'json.loads':>10s} {'np.load':>8s} {'load/json':>9s} "
              f"{'full-val s':>10s}")  # fmt: skip
    print(header)
    for size in args.sizes.split(","):
        s, m = (int(v) for v in size.split("x"))
        block = simulate_block(s, m, rng=3).block
        problem = problem_from_block(block)
        blob = npz_bytes(block)
        t_np = best(args.repeat, lambda b: dict(np.load(io.BytesIO(b))), blob)
        for columnar in (False, True):
            text = dumps_problem(problem, columnar=columnar)
            t_w = best(args.repeat, dumps_problem, problem, columnar=columnar)
            t_l = best(args.repeat, loads_problem, text, "bench.json")
            t_j = best(args.repeat, json.loads, text)
            if block.n_observations <= 20_000:
                doc = json.loads(text)
                v = validator_for("block.json")
                t_full = f"{best(1, lambda d, val=v: list(val.iter_errors(d)), doc):10.2f}"
            else:
                t_full = f"{'-':>10s}"
            form = "columnar" if columnar else "readable"
            print(f"{size:>8s} {block.n_observations:7d} {form:>9s} {len(text) / 1e6:6.2f} "
                  f"{t_w:8.3f} {t_l:8.3f} {t_j:10.4f} {t_np:8.4f} {t_l / t_j:9.1f} {t_full}")  # fmt: skip


if __name__ == "__main__":
    main()
