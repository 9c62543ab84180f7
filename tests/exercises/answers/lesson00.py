"""Lesson 00: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson00.py``.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import norm


def _sol_sigma0(v, sigma, r):
    return np.sqrt(np.sum((v / sigma) ** 2) / r)


def _sol_redundancy(n_images, n_tie, n_control, n_rays):
    return 2 * n_rays - 6 * n_images - 3 * n_tie


def _sol_critical(alpha):
    return norm.isf(alpha / 2)


def _redundancy_numbers(A, sigma, weighted=True):
    P = 1 / sigma**2 if weighted else np.ones_like(sigma)
    N = A.T @ (P[:, None] * A)
    return 1 - np.einsum("ij,jk,ik->i", A, np.linalg.inv(N), A) * P


def _sol_normalized(A, v, sigma):
    return v / (sigma * np.sqrt(_redundancy_numbers(A, sigma)))


SOLUTIONS = {
    "check_sigma0": _sol_sigma0,
    "check_redundancy": _sol_redundancy,
    "check_critical_value": _sol_critical,
    "check_normalized": _sol_normalized,
}

MUTANTS = {
    "check_sigma0": {
        "no weights": lambda v, s, r: np.sqrt(np.sum(v**2) / r),
        "divides by n": lambda v, s, r: np.sqrt(np.sum((v / s) ** 2) / len(v)),
        "no sqrt": lambda v, s, r: np.sum((v / s) ** 2) / r,
        "1/sigma": lambda v, s, r: np.sqrt(np.sum(v**2 / s) / r),
    },
    "check_redundancy": {
        "one observation per ray": lambda m, t, k, n: n - 6 * m - 3 * t,
        "control as unknowns": lambda m, t, k, n: 2 * n - 6 * m - 3 * (t + k),
        "7 per image": lambda m, t, k, n: 2 * n - 7 * m - 3 * t,
    },
    "check_critical_value": {
        "one-sided": lambda a: norm.isf(a),
        "percent": lambda a: norm.isf(a / 200),
    },
    "check_normalized": {
        "v/sigma": lambda A, v, s: v / s,
        "no sqrt": lambda A, v, s: v / (s * _redundancy_numbers(A, s)),
        "unweighted r": lambda A, v, s: (
            v / (s * np.sqrt(_redundancy_numbers(A, s, weighted=False)))
        ),
    },
}
