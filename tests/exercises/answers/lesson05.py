"""Lesson 05: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson05.py``.
"""

from __future__ import annotations

import numpy as np

import orientviz as ov
from orientviz.orientation import relative as rel
from orientviz.orientation import schemes as sch


def _sol_design(X, Y, Z, b):
    q = Y / Z
    return np.column_stack([np.ones_like(X), -q, -Z * (1 + q * q), -(b - X) * q, -(b - X)])


def _design_fd(X, Y, Z, b, h=1e-7):
    """The numeric shortcut: central differences of one's own rigorous parallax."""
    P = np.column_stack([X, Y, Z])

    def parallax(e):
        xy1 = -152.7 * P[:, :2] / P[:, 2:]
        uvw = (P - np.array([b, e[0], e[1]])) @ ov.matrix_from_opk(*e[2:])
        xy2 = -152.7 * uvw[:, :2] / uvw[:, 2:]
        return b / (xy1[:, 0] - xy2[:, 0]) * (xy1[:, 1] - xy2[:, 1])

    return np.column_stack([(parallax(e) - parallax(-e)) / (2 * h) for e in np.eye(5) * h])


def _sol_parallax(xy1, xy2, b):
    lam = b / (xy1[:, 0] - xy2[:, 0])
    return lam * (xy1[:, 1] - xy2[:, 1])


def _sol_six_point_residuals(p, w, mistake=None):
    # I − H projects onto the one direction w (wᵀA = 0): v = −w wᵀp / wᵀw, r_i = w_i² / wᵀw
    ww = w @ w
    v = -w * (w @ p) / ww
    r = w * w / ww
    if mistake == "p - Ad":
        v = -v
    elif mistake == "hat diagonal":
        r = 1.0 - r
    elif mistake == "mean share":
        r = np.full(6, (6 - 5) / 6)
    elif mistake == "no wTw":
        v, r = -w * (w @ p), w * w
    return v, r


def _sol_condition(p, X, Y, Z, b):
    w = np.linalg.svd(_sol_design(X, Y, Z, b).T)[2][-1]
    return 2.0 * (w / w[0]) @ p


def _sol_scheme_sigma(d, sigma, b, h, how="right"):
    """Gruber's six flat points with rows at Y = 0, ±d (``how``: a wrong variant)."""
    if how == "spread":
        d = d / 2
    X = np.array([0.0, b, 0.0, b, 0.0, b])
    Y = np.array([0.0, 0.0, d, d, -d, -d])
    A = _sol_design(X, Y, np.full(6, -h), b)
    if how == "inverse of the diagonal":
        return sigma / np.sqrt(np.diag(A.T @ A))
    s = sigma * np.sqrt(np.diag(np.linalg.inv(A.T @ A)))
    return s**2 if how == "variances" else s


def _kovarik_iteration(xy1, xy2, c, b, tol=1e-9, max_iter=20, mistake=None):
    e = np.zeros(5)
    if mistake == "one_step":
        max_iter = 1
    steps = []
    for _ in range(max_iter):
        # 1. the rigorous y-parallaxes of the pair as it stands: rays meet in X and Z
        B = np.array([b, e[0], e[1]])
        d1 = np.column_stack([xy1, np.full(len(xy1), -c)])
        seq = "pok" if mistake == "pok" else "opk"
        d2 = np.column_stack([xy2, np.full(len(xy2), -c)]) @ (
            ov.matrix_from_opk(*e[2:], seq)
            if mistake == "R_transposed"
            else ov.matrix_from_opk(*e[2:], seq).T
        )
        det = -d1[:, 0] * d2[:, 2] + d2[:, 0] * d1[:, 2]
        lam1 = (-B[0] * d2[:, 2] + d2[:, 0] * B[2]) / det
        lam2 = (d1[:, 0] * B[2] - d1[:, 2] * B[0]) / det
        X, Y, Z = (lam1[:, None] * d1).T  # model points on the left rays
        p = Y - (B[1] + lam2 * d2[:, 1])  # Y_left − Y_right
        if mistake == "sign":
            p = -p
        # 2. the corrections that clear them (your design matrix), 3. apply, repeat
        d = np.linalg.lstsq(_sol_design(X, Y, Z, b), p, rcond=None)[0]
        e = e + d
        steps.append(np.abs(d).max())
        if steps[-1] < tol:
            break
    return e, steps


def _sol_relative_from_exterior(X01, R1, X02, R2, b, mistake=None):
    R = R1.T @ R2
    if mistake == "R_transposed":
        R = R.T
    elif mistake == "object_frame":
        R = R2 @ R1.T
    B = R1.T @ (X02 - X01) if mistake != "base_not_rotated" else X02 - X01
    if mistake != "not_scaled":
        B = B * b / B[0]
    ang = np.array(ov.opk_from_matrix(R))
    if mistake == "degrees":
        ang = np.degrees(ang)
    return np.r_[B[1], B[2], ang]


def _middle_users(X, Y, Z, b, mistake=None):
    A = _sol_design(X, Y, Z, b)
    G = np.linalg.pinv(A)
    names = ("by", "bz", "omega", "phi", "kappa")
    if mistake == "design":
        return {
            n for j, n in enumerate(names) if np.abs(A[6:, j]).max() > 1e-9 * np.abs(A[:, j]).max()
        }
    rows = slice(0, 3) if mistake == "first three" else slice(6, 9)
    return {n for j, n in enumerate(names) if np.abs(G[j, rows]).max() > 1e-9 * np.abs(G[j]).max()}


def _kovarik_library_loop(xy1, xy2, c, b, tol=1e-9, max_iter=20):
    """The iteration around the library's rigorous parallax and design matrix (refused)."""
    e, steps = np.zeros(5), []
    for _ in range(max_iter):
        p, pts = rel.y_parallax(xy1, xy2, c, rel.PairState.from_elements(e, b))
        A = rel.design_dependent(pts[:, 0], pts[:, 1], pts[:, 2], b)
        d = np.linalg.lstsq(A, p, rcond=None)[0]
        e, steps = e + d, steps + [np.abs(d).max()]
        if steps[-1] < tol:
            break
    return e, steps


SOLUTIONS = {
    "check_middle_users": _middle_users,
    "check_relative_from_exterior": _sol_relative_from_exterior,
    "check_kovarik_iteration": _kovarik_iteration,
    "check_design": _sol_design,
    "check_parallax": _sol_parallax,
    "check_six_point_residuals": _sol_six_point_residuals,
    "check_condition": _sol_condition,
    "check_scheme_sigma": _sol_scheme_sigma,
}

MUTANTS = {
    "check_middle_users": {
        "the library's G": lambda X, Y, Z, b: {
            n
            for n, row in zip(rel.DEPENDENT, sch.influence(rel.design_dependent(X, Y, Z, b)))
            if np.abs(row[6:]).max() > 1e-9 * np.abs(row).max()
        },
        "design": lambda *a: _middle_users(*a, mistake="design"),
        "first three": lambda *a: _middle_users(*a, mistake="first three"),
        "flat answer": lambda *a: {"by", "bz", "omega"},
    },
    "check_relative_from_exterior": {
        k: (lambda *a, k=k: _sol_relative_from_exterior(*a, mistake=k))
        for k in ("R_transposed", "object_frame", "base_not_rotated", "not_scaled", "degrees")
    },
    "check_kovarik_iteration": {
        k: (lambda *a, k=k: _kovarik_iteration(*a, mistake=k))
        for k in ("one_step", "sign", "R_transposed")
    }
    | {
        "around the library's parallax": _kovarik_library_loop,
        "pok": lambda *a: _kovarik_iteration(*a, mistake="pok"),
    },
    "check_design": {
        "y'' - y'": lambda X, Y, Z, b: -_sol_design(X, Y, Z, b),
        "phi and kappa swapped": lambda X, Y, Z, b: _sol_design(X, Y, Z, b)[:, [0, 1, 2, 4, 3]],
        "Kovarik signs": lambda X, Y, Z, b: _sol_design(X, Y, Z, b) * [1, -1, 1, 1, -1],
        "the stand-in (the library's)": rel.design_dependent,
        "own central differences": _design_fd,
        "1 - Y^2/Z^2": lambda X, Y, Z, b: (
            _sol_design(X, Y, Z, b)
            - np.column_stack([0 * X, 0 * X, -2 * Z * (Y / Z) ** 2, 0 * X, 0 * X])
        ),
    },
    "check_parallax": {
        "Y_right - Y_left": lambda xy1, xy2, b: -_sol_parallax(xy1, xy2, b),
        "image difference": lambda xy1, xy2, b: xy1[:, 1] - xy2[:, 1],
        # the lesson's stand-in (its c is 152.7 mm, as the check's)
        "the stand-in (the library's)": lambda xy1, xy2, b: rel.y_parallax(
            xy1, xy2, 152.7, rel.PairState.from_elements(np.zeros(5), b)
        )[0],
    },
    "check_six_point_residuals": {
        k: (lambda *a, k=k: _sol_six_point_residuals(*a, mistake=k))
        for k in ("p - Ad", "hat diagonal", "mean share", "no wTw")
    }
    | {"one array": lambda *a: _sol_six_point_residuals(*a)[0]},
    "check_condition": {
        "the library": lambda p, X, Y, Z, b: sch.condition_misclosure(p, X, Y, Z, b)[0],
        "flat form with relief": lambda p, X, Y, Z, b: (
            np.array([2.0, -2.0, -1.0, 1.0, -1.0, 1.0]) @ p
        ),
        "sign": lambda p, X, Y, Z, b: -_sol_condition(p, X, Y, Z, b),
    },
    "check_scheme_sigma": {
        how: (lambda d, s, b, h, how=how: _sol_scheme_sigma(d, s, b, h, how))
        for how in ("inverse of the diagonal", "variances", "spread")
    }
    | {
        "sigma squared": lambda d, s, b, h: s * _sol_scheme_sigma(d, s, b, h),
        "the library": lambda d, s, b, h: sch.scheme_precision("gruber6", b, d, -h, sigma=s)[0],
    },
}
