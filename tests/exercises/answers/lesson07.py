"""Lesson 07: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson07.py``.
"""

from __future__ import annotations

import numpy as np


def _sol_similarity(x, X, fix=True, symmetric=False, transpose=False):
    xm, Xm = x.mean(0), X.mean(0)
    xc, Xc = x - xm, X - Xm
    U, S, Vt = np.linalg.svd(xc.T @ Xc)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T)) if fix else 1.0])
    R = Vt.T @ D @ U.T
    m = (
        np.sqrt((Xc**2).sum() / (xc**2).sum())
        if symmetric
        else np.trace(np.diag(S) @ D) / (xc**2).sum()
    )
    if transpose:
        R = R.T
    return m, R, Xm - m * R @ xm


def _sol_model(X, m, R, T):
    return (X - T) @ R / m


def _sol_design(x, m, R):
    Rx = x @ R.T
    A = np.zeros((3 * len(x), 7))
    for i, p in enumerate(Rx):
        A[3 * i : 3 * i + 3, :3] = np.eye(3)
        A[3 * i : 3 * i + 3, 3:6] = -m * np.array(
            [[0, -p[2], p[1]], [p[2], 0, -p[0]], [-p[1], p[0], 0]]
        )
        A[3 * i : 3 * i + 3, 6] = p
    return A


def _sol_free_axis(x_control, how="line"):
    """The direction of the line through the control points (or a wrong answer)."""
    xc = x_control - x_control.mean(axis=0)
    V = np.linalg.svd(xc)[2]
    if how == "normal":
        return V[-1]
    if how == "centroid":
        return x_control.mean(axis=0) / np.linalg.norm(x_control.mean(axis=0))
    if how == "not unit":
        return x_control[-1] - x_control[0]
    return V[0]


def _model_axes_design(x, m, R):
    A = _sol_design(x, m, R)
    for i, p in enumerate(x):
        K = np.array([[0, -p[2], p[1]], [p[2], 0, -p[0]], [-p[1], p[0], 0]])
        A[3 * i : 3 * i + 3, 3:6] = -m * R @ K
    return A


def _similarity_gn(x, X, sigma, observed, start, tol=1e-10, max_iter=20, mistake=None):
    m, R, T = start
    rows = observed.ravel()
    p = 1.0 / sigma.ravel()[rows] ** 2
    if mistake == "no_weights":
        p = np.ones_like(p)
    if mistake == "one_step":
        max_iter = 1
    for _ in range(max_iter):
        A = _sol_design(x, m, R)[rows]
        dl = (X - (T + m * x @ R.T)).ravel()[rows]  # observed − computed
        N = A.T @ (p[:, None] * A)
        dx = np.linalg.solve(N, A.T @ (p * dl))
        T = T + dx[:3]
        a = dx[3:6]  # small rotation about the object axes
        angle = np.linalg.norm(a)
        K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]]) / max(angle, 1e-300)
        Ra = np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K  # Rodrigues
        R = R @ Ra if mistake == "right_side" else Ra @ R
        m = m + dx[6]
        if np.max(np.abs(dx) * np.sqrt(np.diag(N))) < tol:
            break
    v = (T + m * x @ R.T - X).ravel()[rows]
    r = rows.sum() if mistake == "r_nobs" else rows.sum() - 7
    s0 = v @ (p * v) / r if mistake == "no_sqrt" else np.sqrt(v @ (p * v) / r)
    return m, R, T, s0


def _design_fd(x, m, R, h=1e-6):
    """The numeric shortcut: central differences of X = T + m R(α) R x (Rodrigues)."""
    from orientviz.rotation import matrix_from_rotvec

    def f(q):
        return (q[:3] + q[6] * x @ (matrix_from_rotvec(q[3:6]) @ R).T).ravel()

    q0 = np.r_[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, m]
    return np.column_stack([(f(q0 + e) - f(q0 - e)) / (2 * h) for e in np.eye(7) * h])


SOLUTIONS = {
    "check_similarity_gn": _similarity_gn,
    "check_similarity": _sol_similarity,
    "check_model_coordinates": _sol_model,
    "check_design": _sol_design,
    "check_free_axis": _sol_free_axis,
}

MUTANTS = {
    "check_similarity_gn": {
        k: (lambda *a, k=k: _similarity_gn(*a, mistake=k))
        for k in ("no_weights", "one_step", "r_nobs", "no_sqrt")
    },
    "check_similarity": {
        "transpose": lambda x, X: _sol_similarity(x, X, transpose=True),
        "no reflection fix": lambda x, X: _sol_similarity(x, X, fix=False),
        "symmetric scale": lambda x, X: _sol_similarity(x, X, symmetric=True),
        "T without scale": lambda x, X: (lambda m, R, T: (m, R, X.mean(0) - R @ x.mean(0)))(
            *_sol_similarity(x, X)
        ),
    },
    "check_model_coordinates": {
        "R instead of R^T": lambda X, m, R, T: (X - T) @ R.T / m,
        "times m": lambda X, m, R, T: m * (X - T) @ R,
        "T forgotten": lambda X, m, R, T: X @ R / m,
    },
    "check_design": {
        "own central differences": lambda x, m, R: _design_fd(x, m, R),
        "sign of the rotation columns": lambda x, m, R: (
            _sol_design(x, m, R) * np.r_[1, 1, 1, -1, -1, -1, 1]
        ),
        "m forgotten": lambda x, m, R: (
            _sol_design(x, m, R) * np.r_[1, 1, 1, 1 / m, 1 / m, 1 / m, 1]
        ),
        "scale column times m": lambda x, m, R: _sol_design(x, m, R) * np.r_[1, 1, 1, 1, 1, 1, m],
        "model axes": _model_axes_design,
    },
    "check_free_axis": {
        how: (lambda x, how=how: _sol_free_axis(x, how))
        for how in ("normal", "centroid", "not unit")
    },
}
