"""Lesson 09: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson09.py``.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import null_space as scipy_null_space

from orientviz.exercises.lesson09 import _s_matrix, _sel


def _similarity(xy, rot=(-1, 1), shear=False, scale_twice=False):
    p = len(xy)
    c = xy - xy.mean(axis=0)
    scale = np.column_stack([c[:, 1], c[:, 0]]) if shear else c
    rotation = np.column_stack([rot[0] * c[:, 1], rot[1] * c[:, 0]])
    if scale_twice:
        rotation = 2.0 * c
    return np.column_stack(
        [np.tile([1.0, 0.0], p), np.tile([0.0, 1.0], p), rotation.reshape(-1), scale.reshape(-1)]
    )


def _point_sigma(Q):
    return np.sqrt(np.diag(Q).reshape(-1, 2).sum(axis=1))


def _best_datum(Q, G):
    p = Q.shape[0] // 2
    best, pair = np.inf, None
    for i in range(p):
        for j in range(i + 1, p):
            S = _s_matrix(G, _sel(p, (i, j)))
            worst = _point_sigma(S @ Q @ S.T).max()
            if worst < best:
                best, pair = worst, (i, j)
    return pair


def _central_pair(Q, G):
    return tuple(sorted(np.argsort(_point_sigma(Q))[:2].tolist()))


def _farthest_pair(Q, G):  # the network's coordinates are not given: from Q's largest spread
    p = Q.shape[0] // 2
    # the farthest pair in the checker's network, found from the inner datum's G (its rotation
    # column holds (−ȳ, x̄) up to scale and a rotation of the frame): use distances in that frame
    c = _centred_from_G(G)
    pairs = [(i, j) for i in range(p) for j in range(i + 1, p)]
    return max(pairs, key=lambda q: np.linalg.norm(c[q[0]] - c[q[1]]))


def _centred_from_G(G):
    """Centred point coordinates (up to rotation and scale) from a null-space basis of a distance
    network: the rotation direction orthogonal to both shifts, turned back by 90°."""
    p = G.shape[0] // 2
    tx, ty = np.tile([1.0, 0.0], p), np.tile([0.0, 1.0], p)
    T = np.column_stack([tx, ty])
    R = G - T @ np.linalg.lstsq(T, G, rcond=None)[0]  # remove the shift parts
    r = np.linalg.svd(R, full_matrices=False)[0][:, 0].reshape(-1, 2)  # (−ȳ, x̄) up to a factor
    return np.column_stack([r[:, 1], -r[:, 0]])


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
    "check_similarity_columns": _similarity,
    "check_best_datum": _best_datum,
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
    "check_similarity_columns": {
        "distance defect (3 columns)": lambda xy: _helmert(xy),
        "shear for scale": lambda xy: _similarity(xy, shear=True),
        "rotation sign": lambda xy: _similarity(xy, rot=(1, 1)),
        "scale twice": lambda xy: _similarity(xy, scale_twice=True),
    },
    "check_best_datum": {
        "farthest apart": _farthest_pair,
        "central": _central_pair,
    },
    "check_estimable": {
        k: (lambda k=k: _estimable(k)) for k in ("measured", "distance everywhere", "azimuth")
    },
}
