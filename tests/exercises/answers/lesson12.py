"""Lesson 12: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson12.py``.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import norm


def _normalized(A, l, sigma):
    P = np.diag(1 / sigma**2)
    N = A.T @ P @ A
    v = A @ np.linalg.solve(N, A.T @ P @ l) - l
    Qvv = np.diag(sigma**2) - A @ np.linalg.solve(N, A.T)
    r = np.diag(Qvv @ P)
    return v, r, v / (sigma * np.sqrt(r))


def _snoop_round(A, l, sigma, k):
    _, _, w = _normalized(A, l, sigma)
    i = int(np.argmax(np.abs(w)))
    return i if abs(w[i]) > k else -1


def _mdb(sigma, r, alpha0, beta0):
    return (norm.ppf(1 - alpha0 / 2) + norm.ppf(beta0)) * sigma / np.sqrt(r)


def _external(A, sigma, i, nabla):
    P = np.diag(1 / sigma**2)
    e = np.zeros(len(sigma))
    e[i] = nabla
    return np.linalg.solve(A.T @ P @ A, A.T @ P @ e)


def _snoop_v(A, l, sigma, k):
    v, _, w = _normalized(A, l, sigma)
    i = int(np.argmax(np.abs(v) / sigma))
    return i if abs(w[i]) > k else -1


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
    "check_snoop_round": _snoop_round,
    "check_mdb": _mdb,
    "check_external": _external,
}

MUTANTS = {
    "check_snoop": {
        m: (lambda adjust, n, k, m=m: _snoop(adjust, n, k, m))
        for m in ("all at once", "no abs", "one round")
    },
    "check_normalized": {
        "no sqrt r": lambda A, l, s: (lambda v, r, w: (v, r, v / s))(*_normalized(A, l, s)),
        "r not sqrt": lambda A, l, s: (lambda v, r, w: (v, r, v / (s * r)))(*_normalized(A, l, s)),
        "1 - r": lambda A, l, s: (lambda v, r, w: (v, 1 - r, w))(*_normalized(A, l, s)),
        "unweighted": lambda A, l, s: _normalized(A, l, np.ones_like(s)),
    },
    "check_snoop_round": {
        "largest v/σ": _snoop_v,
        "no threshold": lambda A, l, s, k: _snoop_round(A, l, s, 0.0),
        "signed": lambda A, l, s, k: (lambda w: int(np.argmax(w)) if w.max() > k else -1)(
            _normalized(A, l, s)[2]
        ),
    },
    "check_mdb": {
        "r not sqrt": lambda s, r, a, b: (norm.ppf(1 - a / 2) + norm.ppf(b)) * s / r,
        "one-sided": lambda s, r, a, b: (norm.ppf(1 - a) + norm.ppf(b)) * s / np.sqrt(r),
        "no power": lambda s, r, a, b: norm.ppf(1 - a / 2) * s / np.sqrt(r),
    },
    "check_external": {
        "sign": lambda A, s, i, nb: -_external(A, s, i, nb),
        "unweighted": lambda A, s, i, nb: _external(A, np.ones_like(s), i, nb),
        "N not inverted": lambda A, s, i, nb: (A.T @ A / 1.0) @ _external(A, s, i, nb),
    },
}
