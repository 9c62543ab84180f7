"""Lesson 13: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson13.py``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.linalg

import orientviz as ov
from orientviz.exercises.lesson13 import statoscope_normals_library, statoscope_row_library
from orientviz.rotation import matrix_derivatives, matrix_from_opk


def _statoscope_row(N, n, k, o_col, s, sigma):
    a = np.zeros(len(n))
    a[k], a[o_col] = 1.0, 1.0
    return N + np.outer(a, a) / sigma**2, n + a * s / sigma**2


def _difference_covariance(sigma, m):
    D = np.eye(m)[1:] - np.eye(m)[:-1]
    return sigma**2 * D @ D.T


def _statoscope_normals(N11, n1, Z0, o, s, image, strip, sigma, mistake=None):
    u1, ns = len(n1), len(o)
    N = np.zeros((u1 + ns, u1 + ns))
    N[:u1, :u1] = N11
    n = np.r_[n1, np.zeros(ns)]
    w = 1.0 if mistake == "no weight" else 1.0 / sigma**2
    for s_k, i, j in zip(s, image, strip):
        a = np.zeros(u1 + ns)
        a[6 * i + (0 if mistake == "X0 column" else 2)] = 1.0
        a[u1 + (0 if mistake == "one offset" else j)] = 1.0
        d = {"reading": s_k, "sign": Z0[i] + o[j] - s_k, "no offset": s_k - Z0[i]}.get(
            mistake, s_k - Z0[i] - o[j]
        )
        N += w * np.outer(a, a)
        n += w * a * d
    return N, n


def _skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _gnss_lever_rows(angles, e, mistake=None):
    om, ph, ka = angles
    Ro, Rp, Rk = (matrix_from_opk(om, 0, 0), matrix_from_opk(0, ph, 0), matrix_from_opk(0, 0, ka))
    R = Ro @ Rp @ Rk
    ex, ey, ez = np.eye(3)
    dRk = _skew(ez) @ R if mistake == "kappa left" else R @ _skew(ez)
    dR = [_skew(ex) @ R, Ro @ _skew(ey) @ Rp @ Rk, dRk]
    if mistake == "transposed":
        dR = [d.T for d in dR]
    A = np.zeros((3, 6))
    A[:, :3] = np.eye(3)
    A[:, 3:] = np.column_stack([d @ e for d in dR]) * (-1.0 if mistake == "sign" else 1.0)
    if mistake == "no arm":
        A[:, 3:] = 0.0
    return A


def _from_differences(A0, l0, sig0, s, sigma, mistake=None):
    m = A0.shape[1]
    D = np.eye(m)[1:] - np.eye(m)[:-1]  # (m − 1, m): row k gives s[k+1] − s[k]
    C = sigma**2 * D @ D.T
    if mistake == "independent":
        C = np.diag(np.diag(C))
    W = np.linalg.inv(C) if mistake != "C as weight" else C
    N = A0.T @ (A0 / sig0[:, None] ** 2) + D.T @ W @ D
    n = A0.T @ (l0 / sig0**2) + D.T @ W @ (D @ s)
    return np.linalg.solve(N, n)


def _offset_model(A0, l0, sig0, s, sigma):  # the right heights, but not from the differences
    r, m = A0.shape
    A = np.vstack([np.column_stack([A0, np.zeros(r)]), np.column_stack([np.eye(m), np.ones(m)])])
    w = np.r_[1 / sig0**2, np.full(m, 1 / sigma**2)]
    return np.linalg.solve(A.T @ (w[:, None] * A), A.T @ (w * np.r_[l0, s]))[:m]


def _offset_by_qr(A0, l0, sig0, s, sigma):  # the re-review's bypass: QR + a triangular solve
    r, m = A0.shape
    A = np.vstack([np.column_stack([A0, np.zeros(r)]), np.column_stack([np.eye(m), np.ones(m)])])
    w = np.sqrt(np.r_[1 / sig0**2, np.full(m, 1 / sigma**2)])
    Q, R = np.linalg.qr(A * w[:, None])
    return scipy.linalg.solve_triangular(R, Q.T @ (w * np.r_[l0, s]))[:m]


SOLUTIONS = {
    "check_statoscope_row": _statoscope_row,
    "check_difference_covariance": _difference_covariance,
    "check_statoscope_normals": _statoscope_normals,
    "check_gnss_lever_rows": _gnss_lever_rows,
    "check_from_differences": _from_differences,
}


def _row_with(a_o: float, w: Callable[[float], float], sign_n: float = 1.0):
    def fn(N, n, k, o_col, s, sigma):
        a = np.zeros(len(n))
        a[k], a[o_col] = 1.0, a_o
        return N + np.outer(a, a) * w(sigma), n + sign_n * a * s * w(sigma)

    return fn


MUTANTS = {
    "check_statoscope_row": {
        "no weight": _row_with(1.0, lambda s: 1.0),
        "1/σ": _row_with(1.0, lambda s: 1 / s),
        "minus offset": _row_with(-1.0, lambda s: 1 / s**2),
        "n sign": _row_with(1.0, lambda s: 1 / s**2, -1.0),
        "diagonal only": lambda N, n, k, o, s, sg: (
            N + np.diag(np.eye(len(n))[k] + np.eye(len(n))[o]) / sg**2,
            _statoscope_row(N, n, k, o, s, sg)[1],
        ),
        "the stand-in": statoscope_row_library,
    },
    "check_difference_covariance": {
        "independent": lambda sg, m: 2 * sg**2 * np.eye(m - 1),
        "sigma squared": lambda sg, m: _difference_covariance(sg, m) / 2,
        "positive": lambda sg, m: np.abs(_difference_covariance(sg, m)),
    },
    "check_statoscope_normals": {
        **{
            k: (lambda *args, k=k: _statoscope_normals(*args, mistake=k))
            for k in ("no weight", "X0 column", "one offset", "reading", "sign", "no offset")
        },
        "the stand-in": statoscope_normals_library,
    },
    "check_gnss_lever_rows": {
        "own central differences": lambda a, e: np.hstack(
            [
                np.eye(3),
                np.column_stack(
                    [
                        (ov.matrix_from_opk(*(a + d)) @ e - ov.matrix_from_opk(*(a - d)) @ e) / 2e-6
                        for d in np.eye(3) * 1e-6
                    ]
                ),
            ]
        ),
        **{
            k: (lambda a, e, k=k: _gnss_lever_rows(a, e, k))
            for k in ("no arm", "transposed", "sign", "kappa left")
        },
        "the library's derivatives": lambda a, e: np.column_stack(
            [np.eye(3), np.column_stack([d @ e for d in matrix_derivatives(*a)])]
        ),
    },
    "check_from_differences": {
        k: (lambda A0, l0, sig0, s, sigma, k=k: _from_differences(A0, l0, sig0, s, sigma, k))
        for k in ("independent", "C as weight")
    }
    | {
        "no offset": lambda A0, l0, sig0, s, sigma: np.linalg.solve(
            A0.T @ (A0 / sig0[:, None] ** 2) + np.eye(A0.shape[1]) / sigma**2,
            A0.T @ (l0 / sig0**2) + s / sigma**2,
        ),
        "the offset model again": _offset_model,
        "the offset model by QR": lambda A0, l0, sig0, s, sigma: _offset_by_qr(
            A0, l0, sig0, s, sigma
        ),
    },
}
