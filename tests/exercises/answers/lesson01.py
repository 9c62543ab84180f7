"""Lesson 01: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson01.py``.
"""

from __future__ import annotations

import math

import numpy as np

from orientviz.exercises import lesson01 as checker
from orientviz.exercises.lesson01 import (
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


def _group_sigma0(A, l, sigma, group, how="r_i"):
    p = 1.0 / sigma**2
    N = A.T @ (p[:, None] * A)
    v = A @ np.linalg.solve(N, A.T @ (p * l)) - l
    r_i = 1.0 - p * np.einsum("ij,jk,ik->i", A, np.linalg.inv(N), A)  # diag(I − A N⁻¹ Aᵀ P)
    out = []
    for g in range(int(group.max()) + 1):
        m = group == g
        pvv = np.sum((p * v * v)[m]) if how != "no_weights" else np.sum((v * v)[m])
        r_g = {"n_g": m.sum(), "share": m.sum() * (len(l) - A.shape[1]) / len(l)}.get(
            how, r_i[m].sum()
        )
        out.append(pvv / r_g if how == "squared" else np.sqrt(pvv / r_g))
    return np.array(out)


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
    "check_group_sigma0": _group_sigma0,
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
    "check_group_sigma0": {
        how: (lambda A, l, s, g, how=how: _group_sigma0(A, l, s, g, how))
        for how in ("n_g", "share", "no_weights", "squared")
    },
    "check_gauss_newton_step": {
        "minus": lambda x, st, s, sig: _gn_step(x, st, s, sig, sign=-1),
        "no_weights": lambda x, st, s, sig: _gn_step(x, st, s, sig, weights=False),
        "not_unit": lambda x, st, s, sig: _gn_step(x, st, s, sig, unit=False),
    },
}
