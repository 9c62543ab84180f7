"""Generate ``orientviz/datasets/pair/pair_example.json`` (kind ``pair``, seeded).

Run ``python -m orientviz.datasets.make_pair_example``. The pair comes from the
simulated analog plotter (:func:`orientviz.orientation.plotter.true_pair`): wide angle
c = 152.7 mm, model base 220.7 machine mm, 10 % relief, random relative rotations of
100-150 c; 15 points of Schmid's grid plus 10 random ones, image coordinates with
σ = 3 µm, rounded to 0.1 µm. Units: image mm, model lengths mm, angles c, sequence pok.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..io.kinds.pair import PairData
from ..io.problem import Problem, Units, save_problem
from ..orientation.plotter import PlotterConfig, true_pair
from ..orientation.schemes import fifteen
from ..units import RHO_C

HERE = Path(__file__).resolve().parent / "pair"
SEED = 1968


def make(path: Path | None = None) -> Path:
    """Write the example and return its path (the MANIFEST.json too when ``path`` is None)."""
    rng = np.random.default_rng(SEED)
    cfg = PlotterConfig(relief=0.10)
    pair = true_pair(cfg, rng=rng)
    b, d = cfg.model_base, cfg.k * cfg.projection_distance
    X, Y, _ = fifteen().model_points(b, d, -cfg.projection_distance)
    X = np.r_[X, rng.uniform(0, b, 10)]
    Y = np.r_[Y, rng.uniform(-d, d, 10)]
    P = np.column_stack([X, Y, pair.height(X, Y)])
    xy1, xy2 = pair.images(P)
    xy1 = np.round(xy1 + rng.normal(0, 0.003, xy1.shape), 4)
    xy2 = np.round(xy2 + rng.normal(0, 0.003, xy2.shape), 4)
    ids = [f"P{i + 1}" for i in range(len(X))]
    units = Units(length="mm", angle="c", image="mm")
    data = PairData(ids, xy1, xy2, cfg.c, {}, cfg.sequence)
    problem = Problem(
        "pair", data, units, cfg.sequence, name="pair_example",
        description="relative orientation of a simulated wide-angle pair (Kovarik's plotter set-up)",
        options={"base": b, "sigma": 0.01},
    )  # fmt: skip
    if path is not None:
        return save_problem(problem, path)
    HERE.mkdir(exist_ok=True)
    out = save_problem(problem, HERE / "pair_example.json")
    e = pair.elements
    manifest = {
        "format": "orientviz-datasets/1",
        "datasets": [
            {
                "name": "pair_example",
                "file": "pair_example.json",
                "kind": "pair",
                "form": "readable",
                "description": problem.description,
                "source": f"simulated by orientviz.datasets.make_pair_example (seed {SEED})",
                "units": {"length": "mm", "image": "mm", "angle": "c"},
                "frame": "model frame of orientviz.orientation.relative (X base, Y left, Z up, mm)",
                "licence": "CC0-1.0",
                "truth": {
                    "by_mm": round(float(e[0]), 6),
                    "bz_mm": round(float(e[1]), 6),
                    "omega_c": round(float(e[2] * RHO_C), 6),
                    "phi_c": round(float(e[3] * RHO_C), 6),
                    "kappa_c": round(float(e[4] * RHO_C), 6),
                },  # fmt: skip
                "noise": "image coordinates σ 3 µm, rounded to 0.1 µm",
            }
        ],
    }
    (HERE / "MANIFEST.json").write_text(json.dumps(manifest, indent=1) + "\n", encoding="utf-8")
    return out


if __name__ == "__main__":  # pragma: no cover
    print(make())
