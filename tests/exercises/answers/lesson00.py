"""Lesson 00: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson00.py``.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import norm


def _sol_sigma0(v, sigma, r):
    return np.sqrt(np.sum((v / sigma) ** 2) / r)


def _sol_redundancy(n_images, n_tie, n_control, n_rays, weighted_control=False):
    extra = 3 * n_control if weighted_control else 0  # observations and unknowns alike
    return 2 * n_rays + extra - 6 * n_images - 3 * n_tie - extra


def _sol_flagged_clean(n, k):
    return n * 2 * norm.sf(k)  # both tails


def _sol_after_doubling(sigma0, r_i, w):
    return sigma0 / 2, r_i, w / 2


SOLUTIONS = {
    "check_sigma0": _sol_sigma0,
    "check_redundancy": _sol_redundancy,
    "check_flagged_clean": _sol_flagged_clean,
    "check_after_doubling": _sol_after_doubling,
}

MUTANTS = {
    "check_sigma0": {
        "no weights": lambda v, s, r: np.sqrt(np.sum(v**2) / r),
        "divides by n": lambda v, s, r: np.sqrt(np.sum((v / s) ** 2) / len(v)),
        "no sqrt": lambda v, s, r: np.sum((v / s) ** 2) / r,
        "1/sigma": lambda v, s, r: np.sqrt(np.sum(v**2 / s) / r),
    },
    "check_redundancy": {
        "one observation per ray": lambda m, t, k, n, w: n - 6 * m - 3 * t,
        "control as unknowns": lambda m, t, k, n, w: 2 * n - 6 * m - 3 * (t + k),
        "7 per image": lambda m, t, k, n, w: 2 * n - 7 * m - 3 * t,
        "weighted: unknowns only": lambda m, t, k, n, w: 2 * n - 6 * m - 3 * (t + (k if w else 0)),
        "weighted: observations only": lambda m, t, k, n, w: 2 * n + 3 * k * w - 6 * m - 3 * t,
    },
    "check_flagged_clean": {
        "one-sided": lambda n, k: n * norm.sf(k),
        "one observation": lambda n, k: 2 * norm.sf(k),
        "passes": lambda n, k: n * (1 - 2 * norm.sf(k)),
        "at least one": lambda n, k: 1 - (1 - 2 * norm.sf(k)) ** n,
        "fixed 0.001": lambda n, k: n * 0.001,
    },
    "check_after_doubling": {
        "sigma0 doubled": lambda s, r, w: (2 * s, r, w / 2),
        "r halved": lambda s, r, w: (s / 2, r / 2, w / 2),
        "w unchanged": lambda s, r, w: (s / 2, r, w),
    },
}
