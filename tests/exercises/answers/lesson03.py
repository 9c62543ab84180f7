"""Lesson 03: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson03.py``.
"""

from __future__ import annotations

import numpy as np

from orientviz.exercises.lesson03 import (
    _interior_no_x0,
    _interior_unnormalised,
)
from orientviz.orientation.dlt import dlt_to_orientation


def _shift_origin(L, t, how="right"):
    """P (X + t; 1) = [M | M t + p4] (X; 1), scaled back to L12 = 1 (or a wrong variant)."""
    P = np.append(np.asarray(L, float), 1.0).reshape(3, 4)
    M, p4 = P[:, :3], P[:, 3]
    p4 = M @ (-t if how == "sign" else t) + p4
    if how == "no rescale":
        return np.hstack([M, p4[:, None]]).reshape(-1)[:11]
    if how == "last column":
        return np.hstack([M, (p4 / p4[2])[:, None]]).reshape(-1)[:11]
    if how == "twelve":
        return np.hstack([M, p4[:, None]]).reshape(-1) / p4[2]
    return (np.hstack([M, p4[:, None]]) / p4[2]).reshape(-1)[:11]


def _viewing(L, how="det"):
    P = np.append(np.asarray(L, float), 1.0).reshape(3, 4)
    m3 = P[2, :3] / np.linalg.norm(P[2, :3])
    sign = {"det": -np.sign(np.linalg.det(P[:, :3])), "plus": 1.0, "minus": -1.0}[how]
    return sign * m3 if how != "reversed" else np.sign(np.linalg.det(P[:, :3])) * m3


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


def _affine_fit(machine, calibrated, order="ok", r_minus=6, vsign=1.0):
    n = len(machine)
    A = np.zeros((2 * n, 6))
    A[0::2, 0], A[0::2, 1], A[0::2, 2] = 1.0, machine[:, 0], machine[:, 1]
    A[1::2, 3], A[1::2, 4], A[1::2, 5] = 1.0, machine[:, 0], machine[:, 1]
    l = calibrated.reshape(-1)
    p = np.linalg.solve(A.T @ A, A.T @ l)
    v = A @ p - l
    s0 = np.sqrt(v @ v / (2 * n - r_minus))
    if order == "interleaved":
        p = p[[0, 3, 1, 4, 2, 5]]
    return p, vsign * v, s0


SOLUTIONS = {
    "check_affine_fit": _affine_fit,
    "check_shift_origin": _shift_origin,
    "check_viewing_direction": _viewing,
    "check_interior_from_dlt": _interior,
}

MUTANTS = {
    "check_affine_fit": {
        "interleaved": lambda m, c: _affine_fit(m, c, order="interleaved"),
        "r_2n": lambda m, c: _affine_fit(m, c, r_minus=0),
        "r_2n_3": lambda m, c: _affine_fit(m, c, r_minus=3),
        "v_sign": lambda m, c: _affine_fit(m, c, vsign=-1.0),
    },
    "check_shift_origin": {
        how: (lambda L, t, how=how: _shift_origin(L, t, how))
        for how in ("no rescale", "last column", "sign", "twelve")
    },
    "check_viewing_direction": {
        "m3 as it is": lambda L: _viewing(L, "plus"),
        "minus m3": lambda L: _viewing(L, "minus"),
        "reversed": lambda L: -_viewing(L),
        "the library": lambda L: -dlt_to_orientation(L).R[:, 2],
    },
    "check_interior_from_dlt": {
        "unnormalised": _interior_unnormalised,
        "no_x0": _interior_no_x0,
        "swapped": _interior_swapped,
        "the library": lambda L: (lambda o: np.array([o.c, o.x0, o.y0]))(dlt_to_orientation(L)),
    },
}
