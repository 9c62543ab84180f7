"""Lesson 04: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson04.py``.
"""

from __future__ import annotations

import numpy as np

import orientviz as ov
from orientviz.exercises.lesson04 import _R, _project


def _sol_resection(xy, X, c, sigma, p0, n_iter=10, weighted=True, divide_by_n=False):
    p = np.array(p0, dtype=float)
    s = (
        np.broadcast_to(np.asarray(sigma, dtype=float), xy.shape).ravel()
        if weighted
        else np.ones(xy.size)
    )
    f = lambda q: _project(X, q[:3], _R(q[3:]), c).ravel()  # noqa: E731
    for _ in range(n_iter):
        dl = xy.ravel() - f(p)
        A = np.column_stack([(f(p + h) - f(p - h)) / (2e-6) for h in np.eye(6) * 1e-6])
        dx = np.linalg.solve((A / s[:, None] ** 2).T @ A, (A / s[:, None] ** 2).T @ dl)
        p = p + dx
    v = f(p) - xy.ravel()
    r = xy.size if divide_by_n else xy.size - 6
    return p, float(np.sqrt(np.sum((v / s) ** 2) / r))


def _sol_two_rays(X01, d1, X02, d2):
    b = X02 - X01
    N = np.array([[d1 @ d1, -d1 @ d2], [-d1 @ d2, d2 @ d2]])
    lam1, lam2 = np.linalg.solve(N, [d1 @ b, -d2 @ b])
    return (X01 + lam1 * d1 + X02 + lam2 * d2) / 2


def _two_rays_plus(X01, d1, X02, d2):
    """A mutant: +d1ᵀd2 off the diagonal of the 2×2 normal matrix."""
    b = X02 - X01
    N = np.array([[d1 @ d1, d1 @ d2], [d1 @ d2, d2 @ d2]])
    lam1, lam2 = np.linalg.solve(N, [d1 @ b, -d2 @ b])
    return (X01 + lam1 * d1 + X02 + lam2 * d2) / 2


def _sol_design_X0(X, X0, R, c):
    u, v, w = ((X - X0) @ R).T
    A = np.empty((2 * len(X), 3))
    A[0::2] = c * (R[:, 0][None, :] * w[:, None] - R[:, 2][None, :] * u[:, None]) / w[:, None] ** 2
    A[1::2] = c * (R[:, 1][None, :] * w[:, None] - R[:, 2][None, :] * v[:, None]) / w[:, None] ** 2
    return A


def _sol_sigma_X(x1, B, H, c, sigma_x, how="right"):
    """σ_X of a normal-case ground point seen at x1 in the left image (or a wrong answer)."""
    t = x1 * H / (B * c)  # x1 / p with p = B c / H: the fraction of the base
    g = H / c * sigma_x  # dX = (H/c)((1 − t) dx' + t dx'')
    if how == "midway":
        return g / np.sqrt(2)
    if how == "independent":
        return np.hypot(g, x1 / c * np.sqrt(2) * H / B * H / c * sigma_x)
    if how == "one image":
        return g
    if how == "sum":  # the two parts added, not as squares
        return g * (abs(1 - t) + abs(t))
    return g * np.hypot(1 - t, t)


def _sigmas(xy, X, sigma, c, p, k_all=True):
    """A-priori σ of the six parameters from the points X (image σ one per point)."""
    f = lambda q: _project(X, q[:3], _R(q[3:]), c).ravel()  # noqa: E731
    h = np.array([1e-3, 1e-3, 1e-3, 1e-7, 1e-7, 1e-7])
    A = np.column_stack([(f(p + e) - f(p - e)) / (2 * e[i]) for i, e in enumerate(np.diag(h))])
    P = np.repeat(1.0 / np.asarray(sigma) ** 2, 2)
    return np.sqrt(np.diag(np.linalg.inv(A.T @ (P[:, None] * A))))


def _sol_best_extra_point(
    xy, X, sigma, c, p, xy_new, X_new, sigma_new, k, weighted=True, pick=np.argmin
):
    s = [
        _sigmas(
            None,
            np.vstack([X, X_new[j]]),
            np.r_[sigma, sigma_new[j] if weighted else sigma[0]],
            c,
            p,
        )[k]
        for j in range(len(X_new))
    ]
    return int(pick(s))


def _numeric_X0(X, X0, R, c):  # the lesson's stand-in: central differences of ov.project
    def f(q):
        return ov.project(X, q, R, c).ravel()

    return np.column_stack([(f(X0 + h) - f(X0 - h)) / 2e-3 for h in np.eye(3) * 1e-3])


def _rho_x0_phi(xy, c, H, how="Q"):
    x, y = np.asarray(xy, dtype=float).T
    A = np.zeros((2 * len(x), 2))
    A[0::2, 0], A[0::2, 1] = -c / H / 1.0, c * (1 + x**2 / c**2)  # ∂x/∂X0 [mm/m], ∂x/∂φ [mm/rad]
    A[1::2, 1] = x * y / c  # ∂y/∂φ
    if how == "x only":
        A = A[0::2]
    N = A.T @ A
    Q = N if how == "N" else np.linalg.inv(N)
    return Q[0, 1] if how == "cofactor" else Q[0, 1] / np.sqrt(Q[0, 0] * Q[1, 1])


def _sigma_X_library(x1, B, H, c, s):
    """The lesson's comparison: the library's adjusted intersection of the point (refused)."""
    X = x1 * H / c
    X0 = np.array([[0.0, 0.0, H], [B, 0.0, H]])
    R = np.stack([np.eye(3), np.eye(3)])
    xy = ov.project(np.array([[X, 0.0, 0.0]]), X0[0], R[0], c)
    xy = np.vstack([xy, ov.project(np.array([[X, 0.0, 0.0]]), X0[1], R[1], c)])
    res = ov.intersect_points(xy, [0, 1], [0, 0], X0, R, c, sigma=s)
    return float(res.std(a_posteriori=False)[0, 0])


SOLUTIONS = {
    "check_rho_x0_phi": _rho_x0_phi,
    "check_best_extra_point": _sol_best_extra_point,
    "check_resection": _sol_resection,
    "check_two_rays": _sol_two_rays,
    "check_design_X0": _sol_design_X0,
    "check_sigma_X": _sol_sigma_X,
}

MUTANTS = {
    "check_rho_x0_phi": {
        **{
            how: (lambda xy, c, H, how=how: _rho_x0_phi(xy, c, H, how))
            for how in ("N", "cofactor", "x only")
        },
        "sign of ∂x/∂X0": lambda xy, c, H: _rho_x0_phi(xy, c, -H),
    },
    "check_best_extra_point": {
        "farthest from the centre": lambda xy, X, s, c, p, xyn, Xn, sn, k: int(
            np.argmax(np.hypot(*xyn.T))
        ),
        "weights forgotten": lambda *a: _sol_best_extra_point(*a, weighted=False),
        "always Y0": lambda *a: _sol_best_extra_point(*a[:-1], 1),
        "argmax": lambda *a: _sol_best_extra_point(*a, pick=np.argmax),
    },
    "check_resection": {
        "weights forgotten": lambda *a: _sol_resection(*a, weighted=False),
        "divides by n": lambda *a: _sol_resection(*a, divide_by_n=True),
        "one iteration": lambda *a: _sol_resection(*a, n_iter=1),
        "two iterations": lambda *a: _sol_resection(*a, n_iter=2),
        "no iteration": lambda *a: _sol_resection(*a, n_iter=0),
    },
    "check_two_rays": {
        "point on ray 1": lambda X01, d1, X02, d2: (
            X01
            + np.linalg.solve(
                np.array([[d1 @ d1, -d1 @ d2], [-d1 @ d2, d2 @ d2]]),
                [d1 @ (X02 - X01), -d2 @ (X02 - X01)],
            )[0]
            * d1
        ),
        "sign of the cross term": lambda X01, d1, X02, d2: _two_rays_plus(X01, d1, X02, d2),
    },
    "check_design_X0": {
        "own central differences": lambda X, X0, R, c: np.column_stack(
            [
                (
                    (-c * ((X - X0 - e) @ R)[:, :2] / ((X - X0 - e) @ R)[:, 2:])
                    - (-c * ((X - X0 + e) @ R)[:, :2] / ((X - X0 + e) @ R)[:, 2:])
                ).ravel()
                / 2e-3
                for e in np.eye(3) * 1e-3
            ]
        ),
        "the stand-in (numeric_X0)": _numeric_X0,
        "by X, not X0": lambda X, X0, R, c: -_sol_design_X0(X, X0, R, c),
        "R^T": lambda X, X0, R, c: _sol_design_X0(X, X0, R.T, c),
        "rows x.. then y..": lambda X, X0, R, c: np.vstack(
            [_sol_design_X0(X, X0, R, c)[0::2], _sol_design_X0(X, X0, R, c)[1::2]]
        ),
    },
    "check_sigma_X": {
        how: (lambda x1, B, H, c, s, how=how: _sol_sigma_X(x1, B, H, c, s, how))
        for how in ("midway", "independent", "one image", "sum")
    }
    | {
        "micrometres": lambda x1, B, H, c, s: _sol_sigma_X(x1, B, H, c, s * 1000),
        "the library": lambda x1, B, H, c, s: _sigma_X_library(x1, B, H, c, s),
    },
}
