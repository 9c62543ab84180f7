"""Lesson 14: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson14.py``.
"""

from __future__ import annotations

import numpy as np

from orientviz.exercises.lesson14 import best_pair_library
from orientviz.radar.scene import trilateration_scene


def _ppi_image(P, X0, R, h, m, x0, y0):
    abc = (P - X0) @ R  # rows: Rᵀ (X − X0)
    s_e = np.sqrt(np.sum((P - X0) ** 2, axis=1) - h**2)
    hor = np.hypot(abc[:, 0], abc[:, 1])
    return np.column_stack([x0 + m * s_e * abc[:, 0] / hor, y0 + m * s_e * abc[:, 1] / hor])


def _radius_change(xy, x0, y0, m, h, dm, mistake=None):
    s_e = np.linalg.norm(xy - [x0, y0], axis=1) / m
    s = np.sqrt(s_e**2 + h**2)
    ds = -(s_e**2 / s) * dm / m
    return {
        "s_e": -s_e * dm / m,
        "sign": -ds,
        "relative": ds / s,
        "s/s_e": -s * dm / m,
        "exact": np.sqrt((s_e * m / (m + dm)) ** 2 + h**2) - s,
    }.get(mistake, ds)


def _trilaterate(C, r):
    e1 = (C[1] - C[0]) / np.linalg.norm(C[1] - C[0])
    w = C[2] - C[0]
    i = e1 @ w
    e2 = (w - i * e1) / np.linalg.norm(w - i * e1)
    e3 = np.cross(e1, e2)
    d, j = np.linalg.norm(C[1] - C[0]), e2 @ w
    x = (r[0] ** 2 - r[1] ** 2 + d**2) / (2 * d)
    y = (r[0] ** 2 - r[2] ** 2 + i**2 + j**2 - 2 * i * x) / (2 * j)
    z = np.sqrt(max(r[0] ** 2 - x**2 - y**2, 0.0))
    p1, p2 = C[0] + x * e1 + y * e2 + z * e3, C[0] + x * e1 + y * e2 - z * e3
    return (p1, p2) if p1[2] < p2[2] else (p2, p1)


def _station_sigma(C, X0, idx):
    d = X0 - C[list(idx)]
    J = d / np.linalg.norm(d, axis=1)[:, None]
    return np.sqrt(np.diag(np.linalg.inv(J.T @ J)))


def _steep_pair(C, X0, tri, mistake=None):
    """The two points (not in tri) with the steepest rays from the station: nearest its nadir."""
    free = [k for k in range(len(C)) if k not in tri]
    pairs = [(a, b) for n, a in enumerate(free) for b in free[n + 1 :]]
    if mistake == "spread":
        return max(pairs, key=lambda pr: np.linalg.norm(C[pr[0], :2] - C[pr[1], :2]))
    if mistake == "plan":
        return min(pairs, key=lambda pr: np.hypot(*_station_sigma(C, X0, list(tri) + list(pr))[:2]))
    if mistake == "far from the three":
        centre = C[list(tri), :2].mean(axis=0)
        return tuple(sorted(free, key=lambda k: -np.hypot(*(C[k, :2] - centre)))[:2])
    if mistake == "trial":  # the search the exercise replaces by a rule: refused
        return min(pairs, key=lambda pr: _station_sigma(C, X0, list(tri) + list(pr))[2])
    h = np.hypot(*(C[free, :2] - X0[:2]).T)
    i, j = (free[k] for k in np.argsort(h)[:2])
    return i, j


SOLUTIONS = {
    "check_ppi_image": _ppi_image,
    "check_radius_change": _radius_change,
    "check_trilaterate": _trilaterate,
    "check_steep_pair": _steep_pair,
}

MUTANTS = {
    "check_ppi_image": {
        "true horizontal range": lambda P, X0, R, h, m, x0, y0: (
            np.array([x0, y0]) + m * ((P - X0) @ R)[:, :2]
        ),
        "R not transposed": lambda P, X0, R, h, m, x0, y0: _ppi_image(P, X0, R.T, h, m, x0, y0),
        "no principal point": lambda P, X0, R, h, m, x0, y0: _ppi_image(P, X0, R, h, m, 0.0, 0.0),
        "1/m": lambda P, X0, R, h, m, x0, y0: _ppi_image(P, X0, R, h, 1 / m, x0, y0),
    },
    "check_radius_change": {
        k: (lambda *a, k=k: _radius_change(*a, mistake=k))
        for k in ("s_e", "sign", "relative", "s/s_e", "exact")
    },
    "check_trilaterate": {
        "the library": lambda C, r: tuple(trilateration_scene(C, r)["candidates"]),
        "swapped": lambda C, r: _trilaterate(C, r)[::-1],
        "one root": lambda C, r: (_trilaterate(C, r)[1], _trilaterate(C, r)[1]),
    },
    "check_steep_pair": {
        **{
            k: (lambda C, X0, tri, k=k: _steep_pair(C, X0, tri, k))
            for k in ("spread", "plan", "far from the three", "trial")
        },
        "the stand-in": best_pair_library,
    },
}
