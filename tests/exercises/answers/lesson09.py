"""Lesson 09: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson09.py``.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import null_space as scipy_null_space

from orientviz.exercises.lesson09 import _s_matrix, _sel


def _helmert(xy, rot=(-1, 1), translations=True, scale_instead=False):
    p = len(xy)
    c = xy - xy.mean(axis=0)
    cols = []
    if translations:
        cols += [np.tile([1.0, 0.0], p), np.tile([0.0, 1.0], p)]
    if scale_instead:
        cols.append(c.reshape(-1))
    else:
        cols.append(np.column_stack([rot[0] * c[:, 1], rot[1] * c[:, 0]]).reshape(-1))
    return np.column_stack(cols)


def _s_transform(x, Q, G, pts, mode="ok"):
    e = _sel(len(x) // 2, pts) if mode != "all" else np.ones(len(x))
    S = _s_matrix(G, e)
    if mode == "no_St":
        return S @ x, S @ Q
    if mode == "x_only":
        return S @ x, Q
    return S @ x, S @ Q @ S.T


def _estimable(mistake=None):
    out = {
        "coordinate x of point 1": (False, False),
        "distance 1–4": (True, False),
        "angle at point 5 between points 1 and 6": (True, True),
        "azimuth of the line 1–2": (False, False),
        "ratio of the distances 1–4 and 2–3": (True, True),
    }
    if mistake == "measured":  # estimable = measured: only the distance
        out = {k: (k.startswith("distance"), False) for k in out}
    if mistake == "distance everywhere":
        out["distance 1–4"] = (True, True)
    if mistake == "azimuth":
        out["azimuth of the line 1–2"] = (True, True)
    return out


def _inner_solve(N, b, G, mode="ok"):
    u, d = G.shape
    if mode == "ridge":
        Q = np.linalg.inv(N + G @ G.T)
        return Q @ b, Q
    Gs = G * np.sqrt(np.trace(N) / u)
    M = np.block([[N, Gs], [Gs.T, np.zeros((d, d))]])
    Mi = np.linalg.inv(M)
    if mode == "whole":
        return Mi[:u, :u] @ b, Mi
    Q = Mi[:u, :u]
    return (-1.0 if mode == "sign" else 1.0) * Q @ b, Q


def _sol_null_space(N, rule="roundoff"):
    w, V = np.linalg.eigh(N)
    a = np.abs(w)
    if rule == "roundoff":
        d = int(np.sum(a < len(N) * np.finfo(float).eps * a.max()))
    elif rule == "gap":
        d = int(np.argmax(np.log10(a[1:] + 1e-300) - np.log10(a[:-1] + 1e-300))) + 1
    elif rule == "relative":
        d = int(np.sum(a < 1e-10 * a.max()))
    else:  # absolute
        d = int(np.sum(a < 1e-8))
    return V[:, :d]


SOLUTIONS = {
    "check_null_space": _sol_null_space,
    "check_inner_solve": _inner_solve,
    "check_helmert_columns": lambda xy: _helmert(xy),
    "check_s_transform": lambda x, Q, G, pts: _s_transform(x, Q, G, pts, "ok"),
    "check_estimable": _estimable,
}

MUTANTS = {
    "check_null_space": {
        "relative tolerance": lambda N: _sol_null_space(N, "relative"),
        "largest jump": lambda N: _sol_null_space(N, "gap"),
        "absolute tolerance": lambda N: _sol_null_space(N, "absolute"),
        "rows": lambda N: _sol_null_space(N).T,
        "largest": lambda N: np.linalg.eigh(N)[1][:, -_sol_null_space(N).shape[1] :],
        "the stand-in (scipy's null_space)": scipy_null_space,
    },
    "check_inner_solve": {
        "ridge": lambda N, b, G: _inner_solve(N, b, G, "ridge"),
        "whole_inverse": lambda N, b, G: _inner_solve(N, b, G, "whole"),
        "sign": lambda N, b, G: _inner_solve(N, b, G, "sign"),
    },
    "check_helmert_columns": {
        "rotation_yx": lambda xy: _helmert(xy, rot=(1, 1)),
        "scale_for_rotation": lambda xy: _helmert(xy, scale_instead=True),
        "no_translations": lambda xy: _helmert(xy, translations=False),
    },
    "check_s_transform": {
        "all_points": lambda x, Q, G, pts: _s_transform(x, Q, G, pts, "all"),
        "no_St": lambda x, Q, G, pts: _s_transform(x, Q, G, pts, "no_St"),
        "Q_unchanged": lambda x, Q, G, pts: _s_transform(x, Q, G, pts, "x_only"),
    },
    "check_estimable": {
        k: (lambda k=k: _estimable(k)) for k in ("measured", "distance everywhere", "azimuth")
    },
}
