"""Lesson 12: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson12.py``.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import norm

from orientviz.adjust.gross import redundancy_numbers


def _normalized(A, l, sigma):
    P = np.diag(1 / sigma**2)
    N = A.T @ P @ A
    v = A @ np.linalg.solve(N, A.T @ P @ l) - l
    Qvv = np.diag(sigma**2) - A @ np.linalg.solve(N, A.T)
    r = np.diag(Qvv @ P)
    return v, r, v / (sigma * np.sqrt(r))


def _flag_probability(nabla, sigma, sigma_true, r, k, mistake=None):
    m = np.sqrt(r) * np.abs(nabla) / sigma  # |E(w)|
    s = sigma_true / sigma  # σ of w
    if mistake == "no sigma_true":
        s = 1.0
    elif mistake == "mean by sigma_true":
        m, s = m / s, 1.0
    elif mistake == "variance":
        s = s**2
    if mistake == "one tail":
        return norm.sf((k - m) / s)
    return norm.sf((k - m) / s) + norm.cdf((-k - m) / s)


def _bias_to_noise(r, delta0):
    return delta0 * np.sqrt((1 - r) / r)


def _snoop(adjust, n, k, mistake=None):
    keep = np.ones(n, bool)
    out = []
    if mistake == "all at once":
        w = adjust(keep)
        return [int(i) for i in np.flatnonzero(np.abs(np.nan_to_num(w)) > k)]
    while True:
        w = adjust(keep)
        a = np.nan_to_num(w, nan=-np.inf) if mistake == "no abs" else np.abs(np.nan_to_num(w))
        i = int(np.argmax(a))
        if a[i] <= k:
            return out
        keep[i] = False
        out.append(i)
        if mistake == "one round":
            return out


SOLUTIONS = {
    "check_snoop": _snoop,
    "check_normalized": _normalized,
    "check_new_position": lambda: 12.0,
    "check_flag_probability": _flag_probability,
    "check_bias_to_noise": _bias_to_noise,
}

MUTANTS = {
    "check_snoop": {
        m: (lambda adjust, n, k, m=m: _snoop(adjust, n, k, m))
        for m in ("all at once", "no abs", "one round")
    },
    "check_normalized": {
        "the library's r": lambda A, l, s: (lambda v, r: (v, r, v / (s * np.sqrt(r))))(
            _normalized(A, l, s)[0], redundancy_numbers(A, s)
        ),
        "no sqrt r": lambda A, l, s: (lambda v, r, w: (v, r, v / s))(*_normalized(A, l, s)),
        "r not sqrt": lambda A, l, s: (lambda v, r, w: (v, r, v / (s * r)))(*_normalized(A, l, s)),
        "1 - r": lambda A, l, s: (lambda v, r, w: (v, 1 - r, w))(*_normalized(A, l, s)),
        "unweighted": lambda A, l, s: _normalized(A, l, np.ones_like(s)),
    },
    "check_new_position": {
        "in the cluster": lambda: 1.75,
        "half way": lambda: 8.0,
        "far beyond": lambda: 20.0,
        "just short": lambda: 10.5,
    },
    "check_flag_probability": {
        m: (lambda *a, m=m: _flag_probability(*a, mistake=m))
        for m in ("no sigma_true", "mean by sigma_true", "variance", "one tail")
    }
    | {
        "no sqrt r": lambda nb, s, t, r, k: _flag_probability(nb, s, t, np.ones_like(r), k),
        "not flagging": lambda *a: 1 - _flag_probability(*a),
    },
    "check_bias_to_noise": {
        "the MDB": lambda r, d0: d0 / np.sqrt(r),
        "sqrt(1 - r)": lambda r, d0: d0 * np.sqrt(1 - r),
        "no root": lambda r, d0: d0 * (1 - r) / r,
        "inverted": lambda r, d0: d0 * np.sqrt(r / (1 - r)),
    },
}
