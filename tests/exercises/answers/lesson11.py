"""Lesson 11: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson11.py``.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import norm


def _fit_k1_real(m, ideal, pp):
    z = m - pp
    a = (z * np.sum(z**2, axis=1)[:, None]).ravel()
    return a @ (ideal - z).ravel() / (a @ a)


def _k1_real_swapped(m, ideal, pp):
    z = m - pp
    a = (ideal * np.sum(ideal**2, axis=1)[:, None]).ravel()
    return a @ (z - ideal).ravel() / (a @ a)


def _k1_real_ideal_radius(m, ideal, pp):
    z = m - pp
    a = (z * np.sum(ideal**2, axis=1)[:, None]).ravel()
    return a @ (ideal - z).ravel() / (a @ a)


def _k1_real_x_only(m, ideal, pp):
    z = m - pp
    a = z[:, 0] * np.sum(z**2, axis=1)
    return a @ (ideal - z)[:, 0] / (a @ a)


def _fit_k1(xy, d):
    a = (xy * np.sum(xy**2, axis=1)[:, None]).ravel()
    k1 = a @ d.ravel() / (a @ a)
    v = k1 * a - d.ravel()
    return k1, np.sqrt(v @ v / (a.size - 1))


def _inflation(Q, mistake=None):
    rho = Q[0, 1] / np.sqrt(Q[0, 0] * Q[1, 1])
    f = 1.0 / np.sqrt(1.0 - rho**2)
    return {"variance": f**2, "inverted": 1.0 / f, "rho": abs(rho),
            "abs rho": 1.0 / np.sqrt(1.0 - abs(rho))}.get(mistake, f)  # fmt: skip


def _significant(values, sigmas, alpha):
    return np.abs(values) / sigmas > norm.ppf(1 - alpha / 2)


def _described_share(A, d):
    n, _, k = A.shape
    p = np.linalg.lstsq(A.reshape(2 * n, k), d.ravel(), rcond=None)[0]
    rest = d - A @ p
    return 1 - np.sum(rest**2, axis=0) / np.sum(d**2, axis=0)


def _k1_x_only(xy, d):
    a = xy[:, 0] * np.sum(xy**2, axis=1)
    k1 = a @ d[:, 0] / (a @ a)
    v = k1 * (xy * np.sum(xy**2, axis=1)[:, None]).ravel() - d.ravel()
    return k1, np.sqrt(v @ v / (d.size - 1))


def _share_separate(A, d):
    out = []
    for i in range(2):
        r_i = d[:, i] - A[:, i, :] @ np.linalg.lstsq(A[:, i, :], d[:, i], rcond=None)[0]
        out.append(1 - np.sum(r_i**2) / np.sum(d[:, i] ** 2))
    return np.array(out)


SOLUTIONS = {
    "check_fit_k1": _fit_k1,
    "check_fit_k1_real": _fit_k1_real,
    "check_inflation": _inflation,
    "check_significant": _significant,
    "check_described_share": _described_share,
}

MUTANTS = {
    "check_fit_k1_real": {
        "measured and ideal swapped": _k1_real_swapped,
        "radius of the ideal point": _k1_real_ideal_radius,
        "x equations only": _k1_real_x_only,
        "not reduced to the principal point": lambda m, ideal, pp: _fit_k1_real(
            m, ideal + pp, np.zeros(2)
        ),
        "sign of the residual": lambda m, ideal, pp: -_fit_k1_real(m, ideal, pp),
    },
    "check_fit_k1": {
        "x equations only": _k1_x_only,
        "divide by 2n": lambda xy, d: (
            _fit_k1(xy, d)[0],
            _fit_k1(xy, d)[1] * np.sqrt((d.size - 1) / d.size),
        ),
        "r instead of r²": lambda xy, d: _fit_k1(
            xy / np.sqrt(np.sum(xy**2, axis=1))[:, None] ** 0.5, d
        ),
        "σ0 squared": lambda xy, d: (_fit_k1(xy, d)[0], _fit_k1(xy, d)[1] ** 2),
    },
    "check_inflation": {
        **{
            k: (lambda Q, k=k: _inflation(Q, k)) for k in ("variance", "inverted", "rho", "abs rho")
        },
        # the lesson's stand-in: the right number, with Q inverted instead of derived
        "the stand-in (Q inverted)": lambda Q: np.sqrt(Q[0, 0] * np.linalg.inv(Q)[0, 0]),
        "solve instead of inv": lambda Q: np.sqrt(Q[0, 0] * np.linalg.solve(Q, [1.0, 0.0])[0]),
    },
    "check_significant": {
        "one-sided": lambda v, s, a: np.abs(v) / s > norm.ppf(1 - a),
        "signed": lambda v, s, a: v / s > norm.ppf(1 - a / 2),
        "not divided by σ": lambda v, s, a: np.abs(v) > norm.ppf(1 - a / 2),
        "t squared": lambda v, s, a: (v / s) ** 2 > norm.ppf(1 - a / 2),
    },
    "check_described_share": {
        "remainder": lambda A, d: 1 - _described_share(A, d),
        "separate fits": _share_separate,
        "pooled": lambda A, d: np.full(
            2,
            1
            - np.sum(
                (d - A @ np.linalg.lstsq(A.reshape(-1, A.shape[2]), d.ravel(), rcond=None)[0]) ** 2
            )
            / np.sum(d**2),
        ),
    },
}
