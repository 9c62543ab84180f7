"""Lesson 03: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson03.py``.
"""

from __future__ import annotations

import numpy as np

from orientviz.exercises.lesson03 import (
    _centre_no_one,
    _centre_plus,
    _centre_transpose,
    _interior_no_x0,
    _interior_unnormalised,
    _rows,
)


def _centre(L):
    P = np.append(np.asarray(L, float), 1.0).reshape(3, 4)
    return -np.linalg.solve(P[:, :3], P[:, 3])


def _interior(L):
    P = np.append(np.asarray(L, float), 1.0).reshape(3, 4)
    m1, m2, m3 = P[0, :3], P[1, :3], P[2, :3]
    q = m3 @ m3
    x0, y0 = m1 @ m3 / q, m2 @ m3 / q
    c = np.sqrt(m1 @ m1 / q - x0 * x0)
    return np.array([c, x0, y0])


def _interior_swapped(L):
    c, x0, y0 = _interior(L)
    return np.array([c, y0, x0])


SOLUTIONS = {
    "check_dlt_rows": lambda X, xy: _rows(X, xy, -1.0, False, False),
    "check_projection_centre": _centre,
    "check_interior_from_dlt": _interior,
}

MUTANTS = {
    "check_dlt_rows": {
        "plus_sign": lambda X, xy: _rows(X, xy, 1.0, False, False),
        "swap_xy": lambda X, xy: _rows(X, xy, -1.0, True, False),
        "stacked": lambda X, xy: _rows(X, xy, -1.0, False, True),
    },
    "check_projection_centre": {
        "plus": _centre_plus,
        "transpose": _centre_transpose,
        "no_one": _centre_no_one,
    },
    "check_interior_from_dlt": {
        "unnormalised": _interior_unnormalised,
        "no_x0": _interior_no_x0,
        "swapped": _interior_swapped,
    },
}
