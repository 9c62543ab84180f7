"""Lesson 10: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson10.py``.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import block_diag


def _reduce(U, W, V, bc, bp, mode="ok"):
    Vi = np.linalg.inv(V) if mode != "no_inverse" else V
    S = U - W @ Vi @ W.T if mode != "plus" else U + W @ Vi @ W.T
    r = bc - W @ Vi @ bp if mode != "rhs" else bc
    return S, r


def _back(V, W, bp, dc, mode="ok"):
    if mode == "no_coupling":
        return np.linalg.solve(V, bp)
    if mode == "plus":
        return np.linalg.solve(V, bp + W.T @ dc)
    if mode == "no_inverse":
        return V @ (bp - W.T @ dc)
    return np.linalg.solve(V, bp - W.T @ dc)


def _bandwidth(P, mode="ok"):
    P = np.asarray(P, dtype=bool)
    i, k = np.nonzero(P)
    b = int(np.max(np.abs(i - k), initial=0))
    if mode == "full":
        return 2 * b + 1
    if mode == "with_diagonal":
        return b + 1
    if mode == "row_count":
        return int(P.sum(axis=1).max()) - 1
    return b


def _schur_step(nb, mode="ok"):
    m, q = nb.n_images, nb.n_points
    Vi = np.linalg.inv(nb.V)
    WVi = np.einsum("aqj,qjk->aqk", nb.W.reshape(6 * m, q, 3), Vi).reshape(6 * m, 3 * q)
    if mode == "W_transposed":
        WVi = nb.W.T @ block_diag(*Vi)  # a shape error inside the student's function
    sign = -1.0 if mode != "plus" else 1.0
    S = block_diag(*nb.U) + sign * WVi @ nb.W.T
    r = nb.bc + sign * WVi @ nb.bp
    dc = np.linalg.solve(S, r)
    coupling = nb.W.T @ dc if mode != "no_coupling" else 0.0
    dp = np.einsum("qjk,qk->qj", Vi, (nb.bp - coupling).reshape(q, 3)).reshape(-1)
    return dc, dp


SOLUTIONS = {
    "check_schur_step": _schur_step,
    "check_reduce": lambda U, W, V, bc, bp: _reduce(U, W, V, bc, bp, "ok"),
    "check_back_substitute": lambda V, W, bp, dc: _back(V, W, bp, dc, "ok"),
    "check_bandwidth": lambda P: _bandwidth(P, "ok"),
}

MUTANTS = {
    "check_schur_step": {
        "plus": lambda nb: _schur_step(nb, "plus"),
        "no_coupling": lambda nb: _schur_step(nb, "no_coupling"),
        "W_transposed": lambda nb: _schur_step(nb, "W_transposed"),
    },
    "check_reduce": {
        "plus": lambda U, W, V, bc, bp: _reduce(U, W, V, bc, bp, "plus"),
        "rhs_not_reduced": lambda U, W, V, bc, bp: _reduce(U, W, V, bc, bp, "rhs"),
        "no_inverse": lambda U, W, V, bc, bp: _reduce(U, W, V, bc, bp, "no_inverse"),
    },
    "check_back_substitute": {
        "no_coupling": lambda V, W, bp, dc: _back(V, W, bp, dc, "no_coupling"),
        "plus": lambda V, W, bp, dc: _back(V, W, bp, dc, "plus"),
        "no_inverse": lambda V, W, bp, dc: _back(V, W, bp, dc, "no_inverse"),
    },
    "check_bandwidth": {
        "full": lambda P: _bandwidth(P, "full"),
        "with_diagonal": lambda P: _bandwidth(P, "with_diagonal"),
        "row_count": lambda P: _bandwidth(P, "row_count"),
    },
}
