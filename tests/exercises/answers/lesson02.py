"""Lesson 02: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson02.py``.
"""

from __future__ import annotations

import numpy as np

import orientviz as ov
from orientviz.exercises.lesson02 import F64, GON


def _sol_rotation(omega: float, phi: float, kappa: float) -> F64:
    w, p, k = np.array([omega, phi, kappa]) * GON
    Rw = np.array([[1, 0, 0], [0, np.cos(w), -np.sin(w)], [0, np.sin(w), np.cos(w)]])
    Rp = np.array([[np.cos(p), 0, np.sin(p)], [0, 1, 0], [-np.sin(p), 0, np.cos(p)]])
    Rk = np.array([[np.cos(k), -np.sin(k), 0], [np.sin(k), np.cos(k), 0], [0, 0, 1]])
    return Rw @ Rp @ Rk


def _sol_collinearity(X, X0, R, c, x0, y0):
    u, v, w = ((np.asarray(X) - X0) @ R).T
    return np.column_stack([x0 - c * u / w, y0 - c * v / w])


def _sol_gimbal_pok(phi, kappa, omega):
    return phi - np.sign(omega) * kappa


def _sol_opk(R):
    return (
        np.array([np.arctan2(-R[1, 2], R[2, 2]), np.arcsin(R[0, 2]), np.arctan2(-R[0, 1], R[0, 0])])
        / GON
    )


def _sol_ground(xy, X0, R, c, Z):
    d = np.column_stack([xy, np.full(len(xy), -c)]) @ R.T
    return X0 + ((Z - X0[2]) / d[:, 2])[:, None] * d


def _sol_vertical(xy, c):
    x, y = np.asarray(xy, dtype=float).T
    J = np.zeros((len(x), 2, 3))
    J[:, 0] = np.column_stack([-x * y / c, c * (1 + x**2 / c**2), y])
    J[:, 1] = np.column_stack([-c * (1 + y**2 / c**2), x * y / c, -x])
    return J


def _vertical_fd(xy, c, h=1e-6):
    """The numeric shortcut: points on the rays, turned by ±h, central differences."""
    from orientviz.rotation import matrix_from_opk

    d = np.column_stack([xy, np.full(len(xy), -c)]) * 10.0  # points on the rays (X0 = 0, R = I)

    def image(a):
        uvw = d @ matrix_from_opk(*a)
        return -c * uvw[:, :2] / uvw[:, 2:]

    return np.stack([(image(e) - image(-e)) / (2 * h) for e in np.eye(3) * h], axis=2)


def _without_one(xy, c):
    J = _sol_vertical(xy, c)
    J[:, 0, 1] -= c
    J[:, 1, 0] += c
    return J


def _kappa_sign(xy, c):
    J = _sol_vertical(xy, c)
    J[:, :, 2] *= -1
    return J


def _sol_relief(r_top, h, H):
    return np.asarray(r_top) * np.asarray(h) / H


SOLUTIONS = {
    "check_rotation": _sol_rotation,
    "check_collinearity": _sol_collinearity,
    "check_gimbal_pok": _sol_gimbal_pok,
    "check_opk_from_matrix": _sol_opk,
    "check_ground_point": _sol_ground,
    "check_vertical_partials": _sol_vertical,
    "check_relief_displacement": _sol_relief,
}

MUTANTS = {
    "check_rotation": {
        "transpose": lambda w, p, k: _sol_rotation(w, p, k).T,
        "degrees": lambda w, p, k: _sol_rotation(w * 200 / 180, p * 200 / 180, k * 200 / 180),
        "phi-omega-kappa order": lambda w, p, k: (
            _sol_rotation(0, p, 0) @ _sol_rotation(w, 0, 0) @ _sol_rotation(0, 0, k)
        ),
        "flipped sine in R_phi": lambda w, p, k: (
            _sol_rotation(w, 0, 0) @ _sol_rotation(0, -p, 0) @ _sol_rotation(0, 0, k)
        ),
    },
    "check_collinearity": {
        "R instead of R^T": lambda X, X0, R, c, x0, y0: _sol_collinearity(X, X0, R.T, c, x0, y0),
        "sign of c": lambda X, X0, R, c, x0, y0: _sol_collinearity(X, X0, R, -c, x0, y0),
        "no principal point": lambda X, X0, R, c, x0, y0: _sol_collinearity(X, X0, R, c, 0.0, 0.0),
    },
    "check_gimbal_pok": {
        "the opk rule": lambda p, k, w: p + np.sign(w) * k,
        "kappa forgotten": lambda p, k, w: p,
    },
    "check_opk_from_matrix": {
        "the library": lambda R: np.array(ov.opk_from_matrix(R)) / GON,
        "arctan": lambda R: (
            np.array(
                [np.arctan(-R[1, 2] / R[2, 2]), np.arcsin(R[0, 2]), np.arctan(-R[0, 1] / R[0, 0])]
            )
            / GON
        ),
        "radians": lambda R: _sol_opk(R) * GON,
        "degrees": lambda R: _sol_opk(R) * 0.9,
        "transpose": lambda R: _sol_opk(R.T),
    },
    "check_ground_point": {
        "R^T instead of R": lambda xy, X0, R, c, Z: _sol_ground(xy, X0, R.T, c, Z),
        "+c": lambda xy, X0, R, c, Z: _sol_ground(xy, X0, R, -c, Z),
    },
    "check_vertical_partials": {
        "all signs": lambda xy, c: -_sol_vertical(xy, c),
        "1 forgotten": _without_one,
        "omega phi swapped": lambda xy, c: _sol_vertical(xy, c)[:, :, [1, 0, 2]],
        "kappa sign": _kappa_sign,
        "per gon": lambda xy, c: _sol_vertical(xy, c) * np.pi / 200,
        "rows swapped": lambda xy, c: _sol_vertical(xy, c)[:, ::-1],
        "only omega phi kappa of x": lambda xy, c: _sol_vertical(xy, c) * [[1], [0]],
        "own central differences": _vertical_fd,
    },
    "check_relief_displacement": {
        "foot's factor": lambda r, h, H: r * h / (H - h),
        "sign": lambda r, h, H: -r * h / H,
        "h in mm": lambda r, h, H: r * h / (H * 1000.0),
        "h/r": lambda r, h, H: h / H,
    },
}
