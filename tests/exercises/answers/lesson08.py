"""Lesson 08: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson08.py``.
"""

from __future__ import annotations

import numpy as np


def _similarity(x, X):
    xm, Xm = x.mean(0), X.mean(0)
    H = (x - xm).T @ (X - Xm)
    U, S, Vt = np.linalg.svd(H)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    R = Vt.T @ D @ U.T
    scale = np.trace(np.diag(S) @ D) / np.sum((x - xm) ** 2)
    return scale, R, Xm - scale * R @ xm


def _determined(n_full, n_plan, n_height):
    return n_full + n_plan >= 2 and n_full + n_height >= 3


def _conformal(xy, XY, degree):
    z = xy[:, 0] + 1j * xy[:, 1]
    A = np.column_stack([z**k for k in range(degree + 1)])
    return np.linalg.lstsq(A, XY[:, 0] + 1j * XY[:, 1], rcond=None)[0]


def _strips_for(a, b, mu_max):
    return np.inf if b <= 0 else 10.0 ** ((mu_max - a) / b)


def _no_det_fix(x, X):
    xm, Xm = x.mean(0), X.mean(0)
    U, S, Vt = np.linalg.svd((x - xm).T @ (X - Xm))
    R = Vt.T @ U.T
    scale = S.sum() / np.sum((x - xm) ** 2)
    return scale, R, Xm - scale * R @ xm


def _no_centroid(x, X):
    U, S, Vt = np.linalg.svd(x.T @ X)
    R = Vt.T @ np.diag([1, 1, np.sign(np.linalg.det(Vt.T @ U.T))]) @ U.T
    scale = np.linalg.norm(X - X.mean(0)) / np.linalg.norm(x - x.mean(0))
    return scale, R, X.mean(0) - scale * R @ x.mean(0)


def _transpose(x, X):
    s, R, t = _similarity(x, X)
    return s, R.T, t


def _inverse_scale(x, X):
    s, R, t = _similarity(x, X)
    return 1 / s, R, t


def _t_from_origin(x, X):
    s, R, t = _similarity(x, X)
    return s, R, X.mean(0)


def _compose(s1, s2):
    m1, R1, t1 = s1
    m2, R2, t2 = s2
    return m1 * m2, R1 @ R2, m1 * R1 @ t2 + t1


def _sol_intersect_many(X0, R, xy, c, mistake=None):
    if mistake == "R_transposed":
        R = np.transpose(R, (0, 2, 1))
    d = np.einsum("nij,nj->ni", R, np.column_stack([xy, np.full(len(xy), -c)]))
    if mistake != "not_normalised":
        d = d / np.linalg.norm(d, axis=1)[:, None]
    M = np.eye(3)[None] * np.sum(d * d, axis=1)[:, None, None] - d[:, :, None] * d[:, None, :]
    return np.linalg.solve(M.sum(0), np.einsum("nij,nj->i", M, X0))


def _pairwise_midpoints(X0, R, xy, c):
    n = len(X0)
    return np.mean(
        [
            _sol_intersect_many(X0[[i, k]], R[[i, k]], xy[[i, k]], c)
            for i in range(n)
            for k in range(i + 1, n)
        ],
        axis=0,
    )


def _plus_c(X0, R, xy, c):
    d = np.einsum("nij,nj->ni", R, np.column_stack([xy, np.full(len(xy), c)]))
    d = d / np.linalg.norm(d, axis=1)[:, None]
    M = np.eye(3)[None] - d[:, :, None] * d[:, None, :]
    return np.linalg.solve(M.sum(0), np.einsum("nij,nj->i", M, X0))


SOLUTIONS = {
    "check_intersect_many": _sol_intersect_many,
    "check_compose": _compose,
    "check_determined": _determined,
    "check_conformal": _conformal,
    "check_strips_for": _strips_for,
}

MUTANTS = {
    "check_intersect_many": {
        "R transposed": lambda *a: _sol_intersect_many(*a, mistake="R_transposed"),
        "not normalised": lambda *a: _sol_intersect_many(*a, mistake="not_normalised"),
        "pairwise midpoints": _pairwise_midpoints,
        "+c": _plus_c,
    },
    "check_compose": {
        "order": lambda s1, s2: _compose(s2, s1),
        "no scale in t": lambda s1, s2: (s1[0] * s2[0], s1[1] @ s2[1], s1[1] @ s2[2] + s1[2]),
        "no rotation in t": lambda s1, s2: (s1[0] * s2[0], s1[1] @ s2[1], s1[0] * s2[2] + s1[2]),
    },
    "check_determined": {
        "counting": lambda f, p, h: 3 * f + 2 * p + h >= 7,
        "two heights": lambda f, p, h: f + p >= 2 and f + h >= 2,
        "plan points ignored": lambda f, p, h: f >= 2 and f + h >= 3,
        "one plan point": lambda f, p, h: f + p >= 1 and f + h >= 3,
        "yes instead of True": lambda f, p, h: "yes" if f + p >= 2 and f + h >= 3 else False,
    },
    "check_conformal": {
        "reversed": lambda xy, XY, d: _conformal(xy, XY, d)[::-1],
        "no constant": lambda xy, XY, d: np.r_[
            0,
            np.linalg.lstsq(
                np.column_stack([(xy[:, 0] + 1j * xy[:, 1]) ** k for k in range(1, d + 1)]),
                XY[:, 0] + 1j * XY[:, 1],
                rcond=None,
            )[0],
        ],
        "conjugate pairing": lambda xy, XY, d: _conformal(xy * [1, -1], XY, d),
    },
    "check_strips_for": {
        "natural log": lambda a, b, m: np.inf if b <= 0 else np.exp((m - a) / b),
        "a forgotten": lambda a, b, m: np.inf if b <= 0 else 10.0 ** (m / b),
        "exponent only": lambda a, b, m: np.inf if b <= 0 else (m - a) / b,
        "b <= 0 not handled": lambda a, b, m: 10.0 ** ((m - a) / b),
    },
}
