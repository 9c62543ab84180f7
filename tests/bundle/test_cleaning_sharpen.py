"""Sharpened screening of fast data snooping: never above the exact 2-D statistic."""

from __future__ import annotations

import numpy as np

import orientviz as ov
from orientviz.adjust.gross2d import statistic_2d
from orientviz.bundle import bundle_solver


def _T(adj):
    r = np.nan_to_num(adj.redundancy_numbers).reshape(-1, 2)
    z = np.nan_to_num(adj.normalized_residuals).reshape(-1, 2) * np.sqrt(r)
    return statistic_2d(z, r, np.nan_to_num(adj.redundancy_xy))[0]


def test_sharpened_screening_is_bounded_by_the_exact_test():
    sim = ov.simulate_block(4, 10, rng=3, n_check=0, gross={"count": 6, "size_mm": (0.05, 0.2)})
    block = sim.block
    n = block.n_observations
    sharp = bundle_solver(block, redundancy="local", sharpen=True)
    plain = bundle_solver(block, redundancy="local")
    exact = bundle_solver(block)
    w = np.ones(2 * n)
    sharp(w, "exact")  # the exact round whose blocks sharpen the screening
    plain(w, "exact")
    w[2 * sim.info["gross"]["index"][:, None] + np.arange(2)] = 0.0  # leave the errors out
    T_sharp, T_plain, T_exact = _T(sharp(w)), _T(plain(w)), _T(exact(w))
    kept = w[0::2] > 0
    # leaving rays out only shrinks the redundancy blocks: both screenings are bounded by
    # the exact statistic (up to the last Gauss-Newton step of the screening round)
    assert np.all(T_sharp[kept] <= T_exact[kept] * 1.02 + 0.02)
    assert np.all(T_plain[kept] <= T_exact[kept] * 1.02 + 0.02)
    # and the sharpened one is closer to it
    assert np.all(T_sharp[kept] >= T_plain[kept] - 1e-9)
    gap_sharp = np.sum(T_exact[kept] - T_sharp[kept])
    gap_plain = np.sum(T_exact[kept] - T_plain[kept])
    assert gap_sharp < 0.5 * gap_plain
