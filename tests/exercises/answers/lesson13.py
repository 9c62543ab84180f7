"""Lesson 13: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson13.py``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from orientviz.exercises.lesson13 import statoscope_row_library


def _statoscope_row(N, n, k, o_col, s, sigma):
    a = np.zeros(len(n))
    a[k], a[o_col] = 1.0, 1.0
    return N + np.outer(a, a) / sigma**2, n + a * s / sigma**2


def _difference_covariance(sigma, m):
    D = np.eye(m)[1:] - np.eye(m)[:-1]
    return sigma**2 * D @ D.T


def _gnss_rows(k, t, strip, m, n_strips):
    A = np.zeros((3, 3 * m + 6 * n_strips))
    A[:, 3 * k : 3 * k + 3] = np.eye(3)
    A[:, 3 * m + 3 * strip : 3 * m + 3 * strip + 3] = np.eye(3)
    A[:, 3 * m + 3 * n_strips + 3 * strip : 3 * m + 3 * n_strips + 3 * strip + 3] = t * np.eye(3)
    return A


def _from_differences(A0, l0, sig0, s, sigma, mistake=None):
    m = A0.shape[1]
    D = np.eye(m)[1:] - np.eye(m)[:-1]  # (m − 1, m): row k gives s[k+1] − s[k]
    C = sigma**2 * D @ D.T
    if mistake == "independent":
        C = np.diag(np.diag(C))
    W = np.linalg.inv(C) if mistake != "C as weight" else C
    N = A0.T @ (A0 / sig0[:, None] ** 2) + D.T @ W @ D
    n = A0.T @ (l0 / sig0**2) + D.T @ W @ (D @ s)
    return np.linalg.solve(N, n)


def _offset_model(A0, l0, sig0, s, sigma):  # the right heights, but not from the differences
    r, m = A0.shape
    A = np.vstack([np.column_stack([A0, np.zeros(r)]), np.column_stack([np.eye(m), np.ones(m)])])
    w = np.r_[1 / sig0**2, np.full(m, 1 / sigma**2)]
    return np.linalg.solve(A.T @ (w[:, None] * A), A.T @ (w * np.r_[l0, s]))[:m]


SOLUTIONS = {
    "check_statoscope_row": _statoscope_row,
    "check_difference_covariance": _difference_covariance,
    "check_gnss_rows": _gnss_rows,
    "check_from_differences": _from_differences,
}


def _row_with(a_o: float, w: Callable[[float], float], sign_n: float = 1.0):
    def fn(N, n, k, o_col, s, sigma):
        a = np.zeros(len(n))
        a[k], a[o_col] = 1.0, a_o
        return N + np.outer(a, a) * w(sigma), n + sign_n * a * s * w(sigma)

    return fn


MUTANTS = {
    "check_statoscope_row": {
        "no weight": _row_with(1.0, lambda s: 1.0),
        "1/σ": _row_with(1.0, lambda s: 1 / s),
        "minus offset": _row_with(-1.0, lambda s: 1 / s**2),
        "n sign": _row_with(1.0, lambda s: 1 / s**2, -1.0),
        "diagonal only": lambda N, n, k, o, s, sg: (
            N + np.diag(np.eye(len(n))[k] + np.eye(len(n))[o]) / sg**2,
            _statoscope_row(N, n, k, o, s, sg)[1],
        ),
        "the stand-in": statoscope_row_library,
    },
    "check_difference_covariance": {
        "independent": lambda sg, m: 2 * sg**2 * np.eye(m - 1),
        "sigma squared": lambda sg, m: _difference_covariance(sg, m) / 2,
        "positive": lambda sg, m: np.abs(_difference_covariance(sg, m)),
    },
    "check_gnss_rows": {
        "no drift": lambda k, t, s, m, ns: _gnss_rows(k, 0.0, s, m, ns),
        "drift 1": lambda k, t, s, m, ns: _gnss_rows(k, 1.0, s, m, ns),
        "wrong strip": lambda k, t, s, m, ns: _gnss_rows(k, t, (s + 1) % ns, m, ns),
        "minus offset": lambda k, t, s, m, ns: (
            _gnss_rows(k, t, s, m, ns) * np.r_[np.ones(3 * m), -np.ones(3 * ns), np.ones(3 * ns)]
        ),
    },
    "check_from_differences": {
        k: (lambda A0, l0, sig0, s, sigma, k=k: _from_differences(A0, l0, sig0, s, sigma, k))
        for k in ("independent", "C as weight")
    }
    | {
        "no offset": lambda A0, l0, sig0, s, sigma: np.linalg.solve(
            A0.T @ (A0 / sig0[:, None] ** 2) + np.eye(A0.shape[1]) / sigma**2,
            A0.T @ (l0 / sig0**2) + s / sigma**2,
        ),
        "the offset model again": _offset_model,
    },
}
