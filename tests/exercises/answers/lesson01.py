"""Lesson 01: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson01.py``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import chi2

from orientviz.exercises import lesson01 as checker
from orientviz.exercises.lesson01 import (
    _bounds_no_sqrt,
    _bounds_not_divided,
    _bounds_one_sided,
    _ellipse_degrees,
    _ellipse_minor_direction,
    _ellipse_no_half,
    _ellipse_variances,
    _line_wrong,
    _wm_divide_by_n,
    _wm_no_weights_in_sigma0,
    _wm_one_over_sigma,
    _wm_unweighted,
)


def _weighted_mean(h, sigma):
    p = 1.0 / np.asarray(sigma, float) ** 2
    m = float(np.sum(p * h) / np.sum(p))
    v = m - np.asarray(h, float)
    return m, math.sqrt(float(np.sum(p * v * v)) / (len(h) - 1))


def _ellipse(C):
    w, V = np.linalg.eigh(C)
    return math.sqrt(w[1]), math.sqrt(w[0]), math.atan2(V[1, 1], V[0, 1])


def _bounds(r, alpha):
    return (math.sqrt(chi2.ppf(alpha / 2, r) / r), math.sqrt(chi2.ppf(1 - alpha / 2, r) / r))


def _gn_step(x, stations, s, sigma, sign=1.0, weights=True, unit=True):
    return checker._gn_step(x, stations, s, sigma, sign, weights, unit)  # all flags off: right


def _line_fit(X, l, sigma):
    A = np.column_stack([np.ones_like(X), X])
    P = np.diag(1.0 / sigma**2)
    Q = np.linalg.inv(A.T @ P @ A)
    xhat = Q @ A.T @ P @ l
    v = A @ xhat - l
    return xhat, v, np.sqrt(v @ P @ v / (len(l) - 2)), Q


SOLUTIONS = {
    "check_line_fit": _line_fit,
    "check_weighted_mean": _weighted_mean,
    "check_error_ellipse": _ellipse,
    "check_sigma0_bounds": _bounds,
    "check_gauss_newton_step": lambda x, st, s, sig: _gn_step(x, st, s, sig),
}

MUTANTS = {
    "check_line_fit": {
        key: (lambda X, l, s, key=key: _line_wrong(X, l, s, key))
        for key in ("no_weights", "one_over_sigma", "divide_by_n", "Q_is_N", "v_sign")
    },
    "check_weighted_mean": {
        "unweighted": _wm_unweighted,
        "one_over_sigma": _wm_one_over_sigma,
        "divide_by_n": _wm_divide_by_n,
        "sigma0_unweighted": _wm_no_weights_in_sigma0,
    },
    "check_error_ellipse": {
        "variances": _ellipse_variances,
        "minor_direction": _ellipse_minor_direction,
        "degrees": _ellipse_degrees,
        "no_half": _ellipse_no_half,
    },
    "check_sigma0_bounds": {
        "no_sqrt": _bounds_no_sqrt,
        "one_sided": _bounds_one_sided,
        "not_divided": _bounds_not_divided,
    },
    "check_gauss_newton_step": {
        "minus": lambda x, st, s, sig: _gn_step(x, st, s, sig, sign=-1),
        "no_weights": lambda x, st, s, sig: _gn_step(x, st, s, sig, weights=False),
        "not_unit": lambda x, st, s, sig: _gn_step(x, st, s, sig, unit=False),
    },
}
