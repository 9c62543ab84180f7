"""A shipped DBAT block with gross errors planted in a share of its rays (robust-loss tests)."""

from __future__ import annotations

import numpy as np

from orientviz.datasets import __path__ as DATASETS
from orientviz.io.kinds.block import prepare
from orientviz.io.problem import load_problem


def planted_dbat(name: str, *, share: float = 0.02, seed: int = 28):
    """``datasets/dbat/<name>.json`` with ``share`` of its rays moved by 20–50 σ in a random
    direction (``numpy.random.default_rng(seed)``); returns the problem and its prepared block."""
    prob = load_problem(f"{DATASETS[0]}/dbat/{name}.json")
    block, _ = prepare(prob)
    obs = block.observations
    rng = np.random.default_rng(seed)
    k = rng.choice(obs.xy.shape[0], int(round(share * obs.xy.shape[0])), replace=False)
    ang, mag = rng.uniform(0, 2 * np.pi, k.size), rng.uniform(20, 50, k.size)
    obs.xy[k, 0] += mag * np.cos(ang) * obs.sigma[k, 0]
    obs.xy[k, 1] += mag * np.sin(ang) * obs.sigma[k, 1]
    return prob, block
