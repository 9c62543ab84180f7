"""Lesson 16: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson16.py``.
"""

from __future__ import annotations

import numpy as np


def _control_update(Q, idx, sigma):
    Qj = Q[:, idx]
    M = np.linalg.inv(np.diag(np.asarray(sigma) ** 2) + Q[np.ix_(idx, idx)])
    return Q - Qj @ M @ Qj.T


def _control_update_library(Q, idx, sigma):  # the lesson's stand-in: the full inverse
    E = np.eye(len(Q))[idx]
    return np.linalg.inv(np.linalg.inv(Q) + E.T @ np.diag(1 / np.asarray(sigma) ** 2) @ E)


def _largest_scale(sigma_img_mm, c_mm, format_mm, p, target_m, mu_i, mistake=None):
    hb = c_mm / ((1 - p) * format_mm)  # H/B, the same at every scale
    if mistake == "p":
        hb = c_mm / (p * format_mm)
    if mistake == "B/H":
        hb = 1 / hb
    root2 = 1.0 if mistake == "no √2" else np.sqrt(2.0)
    mu = 1.0 if mistake == "no μ" else mu_i
    return target_m / (mu * root2 * sigma_img_mm * 1e-3 * hb)


def _by_hand():
    return ["g02_004", "g04_006"]


def _after_worst(Q, sigma, mistake=None):
    sz = np.sqrt(np.diag(Q)[2::3])
    j = int(np.argmax(sz))
    Qn = _control_update(Q, [3 * j, 3 * j + 1, 3 * j + 2], [sigma] * 3)
    after = np.sqrt(np.diag(Qn)[2::3])
    others = np.delete(np.arange(len(sz)), j)
    if mistake == "second before":
        k = int(others[np.argmax(sz[others])])
    elif mistake == "itself":
        return j, after[j]
    else:
        k = int(others[np.argmax(after[others])])
    if mistake == "variance":
        return k, after[k] ** 2
    if mistake == "before":
        return k, sz[k]
    return k, after[k]


SOLUTIONS = {
    "check_after_worst": _after_worst,
    "check_control_update": _control_update,
    "check_largest_scale": _largest_scale,
    "check_by_hand": _by_hand,
}


def _update_with(inner, sign=-1.0):
    def fn(Q, idx, sigma):
        Qj = Q[:, idx]
        return Q + sign * Qj @ np.linalg.inv(inner(np.asarray(sigma)) + Q[np.ix_(idx, idx)]) @ Qj.T

    return fn


MUTANTS = {
    "check_after_worst": {
        m: (lambda Q, sg, m=m: _after_worst(Q, sg, m))
        for m in ("second before", "itself", "variance", "before")
    },
    "check_control_update": {
        "P instead of P⁻¹": _update_with(lambda s: np.diag(1 / s**2)),
        "σ instead of σ²": _update_with(lambda s: np.diag(s)),
        "plus sign": _update_with(lambda s: np.diag(s**2), sign=1.0),
        "only the point's own block": lambda Q, idx, s: np.where(
            np.isin(np.arange(len(Q))[:, None], idx) & np.isin(np.arange(len(Q))[None, :], idx),
            _control_update(Q, idx, s),
            Q,
        ),
        "the stand-in (a new u × u inverse)": _control_update_library,
        "solve on the enlarged N": lambda Q, idx, s: np.linalg.solve(
            np.linalg.inv(Q)
            + np.eye(len(Q))[idx].T @ np.diag(1 / np.asarray(s) ** 2) @ np.eye(len(Q))[idx],
            np.eye(len(Q)),
        ),
    },
    "check_largest_scale": {
        k: (lambda *args, k=k: _largest_scale(*args, mistake=k))
        for k in ("p", "B/H", "no √2", "no μ")
    },
    "check_by_hand": {
        "corners only (nothing added)": lambda: [],
        "one point in the middle": lambda: ["g03_004"],
        "three points where two do": lambda: ["g02_004", "g04_006", "g03_000"],
        "a point that does not exist": lambda: ["g09_009"],
    },
}
