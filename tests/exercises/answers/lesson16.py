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


def _best_candidate(Q, candidates, sigma):
    worst = []
    for j in candidates:
        idx = [3 * j, 3 * j + 1, 3 * j + 2]
        Qn = _control_update(Q, idx, [sigma] * 3)
        sz = np.sqrt(np.diag(Qn)[2::3])
        worst.append(np.delete(sz, j).max())
    return candidates[int(np.argmin(worst))]


def _best_by(score):
    def fn(Q, candidates, sigma):
        vals = []
        for j in candidates:
            idx = [3 * j, 3 * j + 1, 3 * j + 2]
            sz = np.sqrt(np.diag(_control_update(Q, idx, [sigma] * 3))[2::3])
            vals.append(score(np.delete(sz, j)))
        return candidates[int(np.argmin(vals))]

    return fn


SOLUTIONS = {
    "check_best_candidate": _best_candidate,
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
    "check_best_candidate": {
        "where σ_Z is largest": lambda Q, c, s: c[int(np.argmax(np.sqrt(np.diag(Q)[2::3])[c]))],
        "the first candidate": lambda Q, c, s: c[0],
        "the mean σ_Z instead of the largest": _best_by(np.mean),
        "RMS σ_Z of all points": lambda Q, c, s: min(
            c,
            key=lambda j: np.sqrt(
                np.mean(np.diag(_control_update(Q, [3 * j, 3 * j + 1, 3 * j + 2], [s] * 3))[2::3])
            ),
        ),
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
