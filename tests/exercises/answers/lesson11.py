"""Lesson 11: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson11.py``.
"""

from __future__ import annotations

import numpy as np


def _k1_alone(K, r):
    s6 = np.sum(r**6)
    return K[0] + K[1] * np.sum(r**8) / s6 + K[2] * np.sum(r**10) / s6


def _per_test_alpha(family, m):
    return 1.0 - (1.0 - family) ** (1.0 / m)


def _trough_term(xy):
    return np.column_stack([xy[:, 0] ** 3, np.zeros(len(xy))])


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


def _k1_x_only(xy, d):
    a = xy[:, 0] * np.sum(xy**2, axis=1)
    k1 = a @ d[:, 0] / (a @ a)
    v = k1 * (xy * np.sum(xy**2, axis=1)[:, None]).ravel() - d.ravel()
    return k1, np.sqrt(v @ v / (d.size - 1))


def _k1_alone_format(K, rho, mistake=None):
    if mistake == "no area element":
        return K[0] + K[1] * 7 / 9 * rho**2 + K[2] * 7 / 11 * rho**4
    if mistake == "rim":
        return K[0] + K[1] * rho**2 + K[2] * rho**4
    if mistake == "sampled":  # the numeric shortcut: fit one term to many points drawn evenly
        g = np.random.default_rng(5)
        r = rho * np.sqrt(g.uniform(0.0, 1.0, 200_000))
        return _k1_alone(K, r)
    if mistake == "grid":  # a numerical integral on 2000 rings (midpoint rule)
        r = (np.arange(2000) + 0.5) * rho / 2000
        w = 2 * np.pi * r
        return (K[0] * w @ r**6 + K[1] * w @ r**8 + K[2] * w @ r**10) / (w @ r**6)
    return K[0] + 0.8 * K[1] * rho**2 + 2.0 / 3.0 * K[2] * rho**4


SOLUTIONS = {
    "check_k1_alone_format": _k1_alone_format,
    "check_fit_k1": _fit_k1,
    "check_k1_alone": _k1_alone,
    "check_inflation": _inflation,
    "check_per_test_alpha": _per_test_alpha,
    "check_trough_term": _trough_term,
}

MUTANTS = {
    "check_k1_alone_format": {
        m: (lambda K, rho, m=m: _k1_alone_format(K, rho, m))
        for m in ("no area element", "rim", "sampled", "grid")
    }
    | {"the lens's K1": lambda K, rho: K[0]},
    "check_k1_alone": {
        "the lens's K1": lambda K, r: K[0],
        "K3 forgotten": lambda K, r: K[0] + K[1] * np.sum(r**8) / np.sum(r**6),
        "plain means": lambda K, r: K[0] + K[1] * np.mean(r**2) + K[2] * np.mean(r**4),
        "weights r⁴": lambda K, r: (
            K[0] + K[1] * np.sum(r**6) / np.sum(r**4) + K[2] * np.sum(r**8) / np.sum(r**4)
        ),
        "sign of K2": lambda K, r: _k1_alone(np.array([K[0], -K[1], -K[2]]), r),
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
    "check_per_test_alpha": {
        "Bonferroni": lambda f, m: f / m,
        "the family's level": lambda f, m: f,
        "times m": lambda f, m: min(f * m, 0.99),
        "not rejecting": lambda f, m: (1.0 - f) ** (1.0 / m),
        "turned round": lambda f, m: 1.0 - (1.0 - f) ** m,
    },
    "check_trough_term": {
        "a scale (in the span)": lambda xy: 2.0 * xy,
        "x² in x (in the span too)": lambda xy: np.column_stack([xy[:, 0] ** 2, np.zeros(len(xy))]),
        "x⁵ in x": lambda xy: np.column_stack([xy[:, 0] ** 5, np.zeros(len(xy))]),
        "x³ in y": lambda xy: np.column_stack([np.zeros(len(xy)), xy[:, 0] ** 3]),
        "radial r²": lambda xy: xy * np.sum(xy**2, axis=1)[:, None],
        "the trough itself": lambda xy: xy * (1.0 - 2.0 * (xy[:, 0] / 115.0) ** 2)[:, None],
        "the library's trough": lambda xy: __import__(
            "orientviz.simulate.systematic", fromlist=["unflatness"]
        ).unflatness(5.0)(xy),
    },
}
