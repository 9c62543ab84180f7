"""Lesson 06: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson06.py``.
"""

from __future__ import annotations

import numpy as np


def _eight_point(xy1, xy2, c, rank2=True, scale=True, transpose=False):
    d1 = np.column_stack([xy1, np.full(len(xy1), -c)])
    d2 = np.column_stack([xy2, np.full(len(xy2), -c)])
    M = (d1[:, :, None] * d2[:, None, :]).reshape(-1, 9)
    E = np.linalg.svd(M)[2][-1].reshape(3, 3)
    if rank2:
        U, s, Vt = np.linalg.svd(E)
        E = U @ np.diag([1.0, 1.0, 0.0]) @ Vt
    E = E / np.linalg.norm(E) * (np.sqrt(2.0) if scale else 1.0)
    return E.T if transpose else E


def _dist(E, xy1, xy2, c):
    g = np.column_stack([xy1, np.full(len(xy1), -c)]) @ E
    return np.abs(g[:, 0] * xy2[:, 0] + g[:, 1] * xy2[:, 1] - c * g[:, 2]) / np.hypot(
        g[:, 0], g[:, 1]
    )


def _epipole(E, c, how="right"):
    """The image of the null vector of E (or of Eᵀ, …: the wrong answers)."""
    M = E.T if how == "left" else E
    d = np.linalg.svd(M)[2][-1]
    if how == "no c":
        return d[:2] / d[2]
    return (c if how == "sign" else -c) * d[:2] / d[2]


def _swapped_pair(E, xy1, xy2, c, how="swap test"):
    d = _dist(E, xy1, xy2, c)
    order = np.argsort(d)[::-1]
    if how == "two largest":
        return tuple(order[:2])
    if how == "one-based":
        return tuple(np.asarray(_swapped_pair(E, xy1, xy2, c)) + 1)
    best, pair = np.inf, None
    for a in order[:5]:  # the candidates: the largest distances
        for b in order[:5]:
            if a < b:
                q = xy2.copy()
                q[[a, b]] = q[[b, a]]
                worst = _dist(E, xy1, q, c)[[a, b]].max()
                if worst < best:
                    best, pair = worst, (int(a), int(b))
    return pair


SOLUTIONS = {
    "check_eight_point": _eight_point,
    "check_plane_points": lambda p, q: min(p, 6) + q >= 8,
    "check_epipole": _epipole,
    "check_swapped_pair": _swapped_pair,
}

MUTANTS = {
    "check_eight_point": {
        "no_rank2": lambda a, b, c: _eight_point(a, b, c, rank2=False),
        "not_scaled": lambda a, b, c: _eight_point(a, b, c, scale=False),
        "transposed": lambda a, b, c: _eight_point(a, b, c, transpose=True),
    },
    "check_plane_points": {
        "counting": lambda p, q: p + q >= 8,
        "plane useless": lambda p, q: q >= 8,
        "seven": lambda p, q: min(p, 6) + q >= 7,
        "a string": lambda p, q: "yes" if min(p, 6) + q >= 8 else False,
    },
    "check_epipole": {
        "left": lambda E, c: _epipole(E, c, "left"),
        "sign": lambda E, c: _epipole(E, c, "sign"),
        "no c": lambda E, c: _epipole(E, c, "no c"),
        "largest singular vector": lambda E, c: (
            -c * np.linalg.svd(E)[2][0][:2] / np.linalg.svd(E)[2][0][2]
        ),
    },
    "check_swapped_pair": {
        "two largest": lambda E, a, b, c: _swapped_pair(E, a, b, c, "two largest"),
        "one-based": lambda E, a, b, c: _swapped_pair(E, a, b, c, "one-based"),
    },
}
