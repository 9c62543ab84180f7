"""Lesson 01: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson01.py``.
"""

from __future__ import annotations

import math

import numpy as np

from orientviz.exercises.lesson01 import _line_wrong


def _mean_sigma(sigma, mistake=None):
    sigma = np.asarray(sigma, float)
    n = len(sigma)
    if mistake == "variance":
        return 1 / np.sum(1 / sigma**2), np.sum(sigma**2) / n**2
    if mistake == "mean sigma":
        return np.mean(sigma) / math.sqrt(n), np.mean(sigma) / math.sqrt(n)
    if mistake == "rms":
        return 1 / math.sqrt(np.sum(1 / sigma**2)), math.sqrt(np.mean(sigma**2))
    if mistake == "one over sigma":
        return math.sqrt(n) / np.sum(1 / sigma), math.sqrt(np.sum(sigma**2)) / n
    return 1 / math.sqrt(np.sum(1 / sigma**2)), math.sqrt(np.sum(sigma**2)) / n


def _weakest(stations, x, sigma, mistake=None):
    d = x - stations
    u = d / np.linalg.norm(d, axis=1)[:, None]
    p = np.ones(len(sigma)) if mistake == "unweighted" else 1.0 / sigma**2
    N = u.T @ (p[:, None] * u)
    w, V = np.linalg.eigh(N)  # ascending: N's smallest eigenvalue is C's largest
    if mistake == "strong":
        return V[:, 1]
    if mistake == "weak ray":
        return u[int(np.argmax(sigma))]
    if mistake == "degrees":
        return np.degrees(np.arctan2(V[1, 0], V[0, 0]))
    return V[:, 0]


def _second_difference(x, station, dx, t):
    """The numeric shortcut: ½ (s(x + t dx) − 2 s(x) + s(x − t dx)) / t² in floating point."""
    s = lambda q: np.linalg.norm(q - station)  # noqa: E731
    return 0.5 * (s(x + t * dx) - 2 * s(x) + s(x - t * dx)) / t**2


def _second_order(x, station, dx, mistake=None):
    d = x - station
    s = np.linalg.norm(d)
    u = d / s
    along = u @ dx
    perp = dx - along * u
    return {
        "whole dx": dx @ dx / (2 * s),
        "no half": perp @ perp / s,
        "along": along**2 / (2 * s),
        "sign": -(perp @ perp) / (2 * s),
        "exact": np.linalg.norm(x + dx - station) - s - along,
    }.get(mistake, perp @ perp / (2 * s))


def _group_sigma0(A, l, sigma, group, how="r_i"):
    p = 1.0 / sigma**2
    N = A.T @ (p[:, None] * A)
    v = A @ np.linalg.solve(N, A.T @ (p * l)) - l
    r_i = 1.0 - p * np.einsum("ij,jk,ik->i", A, np.linalg.inv(N), A)  # diag(I − A N⁻¹ Aᵀ P)
    out = []
    for g in range(int(group.max()) + 1):
        m = group == g
        pvv = np.sum((p * v * v)[m]) if how != "no_weights" else np.sum((v * v)[m])
        r_g = {"n_g": m.sum(), "share": m.sum() * (len(l) - A.shape[1]) / len(l)}.get(
            how, r_i[m].sum()
        )
        out.append(pvv / r_g if how == "squared" else np.sqrt(pvv / r_g))
    return np.array(out)


def _line_fit(X, l, sigma):
    A = np.column_stack([np.ones_like(X), X])
    P = np.diag(1.0 / sigma**2)
    Q = np.linalg.inv(A.T @ P @ A)
    xhat = Q @ A.T @ P @ l
    v = A @ xhat - l
    return xhat, v, np.sqrt(v @ P @ v / (len(l) - 2)), Q


SOLUTIONS = {
    "check_line_fit": _line_fit,
    "check_mean_sigma": _mean_sigma,
    "check_weakest_direction": _weakest,
    "check_group_sigma0": _group_sigma0,
    "check_second_order": _second_order,
}

MUTANTS = {
    "check_line_fit": {
        key: (lambda X, l, s, key=key: _line_wrong(X, l, s, key))
        for key in ("no_weights", "one_over_sigma", "divide_by_n", "Q_is_N", "v_sign")
    },
    "check_mean_sigma": {
        k: (lambda sg, k=k: _mean_sigma(sg, k))
        for k in ("variance", "mean sigma", "rms", "one over sigma")
    },
    "check_weakest_direction": {
        k: (lambda st, x, sg, k=k: _weakest(st, x, sg, k))
        for k in ("unweighted", "strong", "weak ray", "degrees")
    },
    "check_group_sigma0": {
        how: (lambda A, l, s, g, how=how: _group_sigma0(A, l, s, g, how))
        for how in ("n_g", "share", "no_weights", "squared")
    },
    "check_second_order": {
        k: (lambda x, st, dx, k=k: _second_order(x, st, dx, k))
        for k in ("whole dx", "no half", "along", "sign", "exact")
    }
    | {
        f"second difference, t {t:g}": (lambda x, st, dx, t=t: _second_difference(x, st, dx, t))
        for t in (1e-2, 1e-3)
    },
}
