"""Lesson 08: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson08.py``.
"""

from __future__ import annotations

import numpy as np


def _similarity(x, X):
    xm, Xm = x.mean(0), X.mean(0)
    H = (x - xm).T @ (X - Xm)
    U, S, Vt = np.linalg.svd(H)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    R = Vt.T @ D @ U.T
    scale = np.trace(np.diag(S) @ D) / np.sum((x - xm) ** 2)
    return scale, R, Xm - scale * R @ xm


def _determined(n_full, n_plan, n_height):
    return n_full + n_plan >= 2 and n_full + n_height >= 3


def _strip_degree(xy, XY, sigma, max_degree, mistake=None):
    from scipy.stats import chi2

    z = xy[:, 0] + 1j * xy[:, 1]
    Z = XY[:, 0] + 1j * XY[:, 1]
    n, s0s = len(z), []
    for d in range(1, max_degree + 1):
        A = np.column_stack([z**k for k in range(d + 1)])
        v = A @ np.linalg.lstsq(A, Z, rcond=None)[0] - Z
        r = n - (d + 1) if mistake == "complex r" else 2 * n - 2 * (d + 1)
        vv = np.sum(np.abs(v) ** 2) / (1.0 if mistake == "no sigma" else sigma**2)
        s0 = np.sqrt(vv / r)
        s0s.append(s0)
        if mistake == "min":
            continue
        if mistake == "two-sided":
            ok = chi2.ppf(0.025, r) / r <= s0**2 <= chi2.ppf(0.975, r) / r
        elif mistake == "le1":
            ok = s0 <= 1.0
        elif isinstance(mistake, float) and mistake > 1.0:  # a fixed bound on σ̂0
            ok = s0 <= mistake
        elif isinstance(mistake, float):  # another level: chi2.ppf(mistake, r)
            ok = s0**2 <= chi2.ppf(mistake, r) / r
        else:
            ok = s0**2 <= chi2.ppf(0.95, r) / r
        if ok:
            return d
    return int(np.argmin(s0s)) + 1 if mistake == "min" else max_degree


def _strips_for(a, b, mu_max):
    return np.inf if b <= 0 else 10.0 ** ((mu_max - a) / b)


def _no_det_fix(x, X):
    xm, Xm = x.mean(0), X.mean(0)
    U, S, Vt = np.linalg.svd((x - xm).T @ (X - Xm))
    R = Vt.T @ U.T
    scale = S.sum() / np.sum((x - xm) ** 2)
    return scale, R, Xm - scale * R @ xm


def _no_centroid(x, X):
    U, S, Vt = np.linalg.svd(x.T @ X)
    R = Vt.T @ np.diag([1, 1, np.sign(np.linalg.det(Vt.T @ U.T))]) @ U.T
    scale = np.linalg.norm(X - X.mean(0)) / np.linalg.norm(x - x.mean(0))
    return scale, R, X.mean(0) - scale * R @ x.mean(0)


def _transpose(x, X):
    s, R, t = _similarity(x, X)
    return s, R.T, t


def _inverse_scale(x, X):
    s, R, t = _similarity(x, X)
    return 1 / s, R, t


def _t_from_origin(x, X):
    s, R, t = _similarity(x, X)
    return s, R, X.mean(0)


def _compose(s1, s2):
    m1, R1, t1 = s1
    m2, R2, t2 = s2
    return m1 * m2, R1 @ R2, m1 * R1 @ t2 + t1


def _sol_intersect_many(X0, R, xy, c, mistake=None):
    if mistake == "R_transposed":
        R = np.transpose(R, (0, 2, 1))
    d = np.einsum("nij,nj->ni", R, np.column_stack([xy, np.full(len(xy), -c)]))
    if mistake != "not_normalised":
        d = d / np.linalg.norm(d, axis=1)[:, None]
    M = np.eye(3)[None] * np.sum(d * d, axis=1)[:, None, None] - d[:, :, None] * d[:, None, :]
    return np.linalg.solve(M.sum(0), np.einsum("nij,nj->i", M, X0))


def _pairwise_midpoints(X0, R, xy, c):
    n = len(X0)
    return np.mean(
        [
            _sol_intersect_many(X0[[i, k]], R[[i, k]], xy[[i, k]], c)
            for i in range(n)
            for k in range(i + 1, n)
        ],
        axis=0,
    )


def _plus_c(X0, R, xy, c):
    d = np.einsum("nij,nj->ni", R, np.column_stack([xy, np.full(len(xy), c)]))
    d = d / np.linalg.norm(d, axis=1)[:, None]
    M = np.eye(3)[None] - d[:, :, None] * d[:, None, :]
    return np.linalg.solve(M.sum(0), np.einsum("nij,nj->i", M, X0))


def _model_jacobian(lam, R, m, mistake=None):
    from orientviz.rotation import skew

    J = np.zeros((len(m), 3, 7))
    J[:, :, :3] = -lam[:, None, None] * (R @ skew(m))
    if mistake == "sign":
        J[:, :, :3] *= -1
    elif mistake == "left":
        J[:, :, :3] = -lam[:, None, None] * skew(np.einsum("kij,kj->ki", R, m))
    J[:, :, 3] = m if mistake == "lambda column" else np.einsum("kij,kj->ki", R, m)
    J[:, :, 4:] = np.eye(3)
    return J


def _model_jacobian_fd(lam, R, m, h):
    """The student's own central differences of λ R exp([θ]×) m + T (the numeric shortcut)."""
    from orientviz.rotation import matrix_from_rotvec

    def f(p):
        E = matrix_from_rotvec(p[:, :3])
        return (lam + p[:, 3])[:, None] * np.einsum("kij,kjl,kl->ki", R, E, m) + p[:, 4:]

    J = np.zeros((len(m), 3, 7))
    for j in range(7):
        e = np.zeros((len(m), 7))
        e[:, j] = h
        J[:, :, j] = (f(e) - f(-e)) / (2 * h)
    return J


def _adjust_models(m, model, point, X, free, sigma, R, T, mistake=None):
    """The independent-model adjustment (Gauss-Newton, dense normal equations)."""
    from orientviz.rotation import matrix_from_rotvec

    n, k = len(R), len(m)
    lam, R, T, X = np.ones(n), R.copy(), T.copy(), X.copy()
    R0, T0 = R.copy(), T.copy()
    if mistake == "whole points":  # a point is fixed only if all of X, Y, Z are given
        free = np.repeat(free.any(axis=1, keepdims=True), 3, axis=1)
    col = np.full(free.shape, -1)
    col[free] = 7 * n + np.arange(free.sum())
    w = np.tile(1.0 / sigma**2, k) if mistake != "no weights" else np.ones(3 * k)
    rows = np.arange(3 * k).reshape(k, 3)
    for _ in range(1 if mistake == "one step" else 20):
        v = lam[model, None] * np.einsum("kij,kj->ki", R[model], m) + T[model] - X[point]
        A = np.zeros((3 * k, 7 * n + int(free.sum())))
        J = _model_jacobian(lam[model], R[model], m)
        if mistake == "left update":
            J[:, :, :3] = -lam[model, None, None] * _skew(np.einsum("kij,kj->ki", R[model], m))
        A[rows[:, :, None], 7 * model[:, None, None] + np.arange(7)] = J
        has = col[point] >= 0
        A[rows[has], col[point][has]] = -1.0
        d = np.linalg.solve(A.T @ (w[:, None] * A), -A.T @ (w * v.ravel()))
        dm = d[: 7 * n].reshape(n, 7)
        R = R @ matrix_from_rotvec(dm[:, :3])
        lam, T = lam + dm[:, 3], T + dm[:, 4:]
        X[free] += d[7 * n :]
        if np.max(np.abs(d)) < 1e-6 * sigma[0]:
            break
    v = (lam[model, None] * np.einsum("kij,kj->ki", R[model], m) + T[model] - X[point]).ravel()
    r = 3 * k - A.shape[1] if mistake != "r without points" else 3 * k - 7 * n
    if mistake == "R transposed":
        R = np.transpose(R, (0, 2, 1))
    if mistake == "start R, T":
        R, T = R0, T0
    if mistake == "T zero":
        T = np.zeros_like(T)
    return lam, R, T, X, np.sqrt(v @ (w * v) / r)


def _skew(v):
    from orientviz.rotation import skew

    return skew(v)


def _strip_polynomial(x, X, dxy, dz, mistake=None):
    """Conformal planimetry (one complex lstsq) and height with cross tilt, fitted to control."""
    w = (x[:, 0] + 1j * x[:, 1] - (x[:, 0].mean() + 1j * x[:, 1].mean())) / 1000.0
    u, v = w.real, w.imag
    plan = ~np.isnan(X[:, 0]) & ~np.isnan(X[:, 1])
    height = ~np.isnan(X[:, 2])
    if mistake == "full control only":
        plan = height = plan & height
    A = np.column_stack([w**k for k in range(dxy + (0 if mistake == "degree" else 1))])
    z, Z = x[:, 0] + 1j * x[:, 1], X[:, 0] + 1j * X[:, 1]
    sign = -1.0 if mistake == "sign" else 1.0
    c = np.linalg.lstsq(A[plan], sign * (Z[plan] - z[plan]), rcond=None)[0]
    n_tilt = {"no tilt": 0, "tilt to d": dz + 1, "tilt too low": dz - 1}.get(mistake, dz)
    B = np.column_stack([u**k for k in range(dz + 1)] + [v * u**k for k in range(n_tilt)])
    e = np.linalg.lstsq(B[height], sign * (X[height, 2] - x[height, 2]), rcond=None)[0]
    zc = z + A @ c
    return np.column_stack([zc.real, zc.imag, x[:, 2] + B @ e])


SOLUTIONS = {
    "check_strip_polynomial": _strip_polynomial,
    "check_model_jacobian": _model_jacobian,
    "check_adjust_models": _adjust_models,
    "check_intersect_many": _sol_intersect_many,
    "check_compose": _compose,
    "check_determined": _determined,
    "check_strip_degree": _strip_degree,
    "check_strips_for": _strips_for,
}

MUTANTS = {
    "check_strip_polynomial": {
        m: (lambda x, X, a, b, m=m: _strip_polynomial(x, X, a, b, mistake=m))
        for m in ("degree", "no tilt", "tilt to d", "tilt too low", "sign", "full control only")
    },
    "check_model_jacobian": {
        "own central differences, h 1e-6": lambda *a: _model_jacobian_fd(*a, 1e-6),
        "own central differences, h 1e-4": lambda *a: _model_jacobian_fd(*a, 1e-4),
        "sign": lambda *a: _model_jacobian(*a, mistake="sign"),
        "left increment": lambda *a: _model_jacobian(*a, mistake="left"),
        "lambda column": lambda *a: _model_jacobian(*a, mistake="lambda column"),
    },
    "check_adjust_models": {
        "no weights": lambda *a: _adjust_models(*a, mistake="no weights"),
        "one step": lambda *a: _adjust_models(*a, mistake="one step"),
        "left update": lambda *a: _adjust_models(*a, mistake="left update"),
        "whole points": lambda *a: _adjust_models(*a, mistake="whole points"),
        "r without points": lambda *a: _adjust_models(*a, mistake="r without points"),
        "R transposed": lambda *a: _adjust_models(*a, mistake="R transposed"),
        "start R, T": lambda *a: _adjust_models(*a, mistake="start R, T"),
        "T zero": lambda *a: _adjust_models(*a, mistake="T zero"),
    },
    "check_intersect_many": {
        "R transposed": lambda *a: _sol_intersect_many(*a, mistake="R_transposed"),
        "not normalised": lambda *a: _sol_intersect_many(*a, mistake="not_normalised"),
        "pairwise midpoints": _pairwise_midpoints,
        "+c": _plus_c,
    },
    "check_compose": {
        "order": lambda s1, s2: _compose(s2, s1),
        "no scale in t": lambda s1, s2: (s1[0] * s2[0], s1[1] @ s2[1], s1[1] @ s2[2] + s1[2]),
        "no rotation in t": lambda s1, s2: (s1[0] * s2[0], s1[1] @ s2[1], s1[0] * s2[2] + s1[2]),
    },
    "check_determined": {
        "counting": lambda f, p, h: 3 * f + 2 * p + h >= 7,
        "two heights": lambda f, p, h: f + p >= 2 and f + h >= 2,
        "plan points ignored": lambda f, p, h: f >= 2 and f + h >= 3,
        "one plan point": lambda f, p, h: f + p >= 1 and f + h >= 3,
        "yes instead of True": lambda f, p, h: "yes" if f + p >= 2 and f + h >= 3 else False,
    },
    "check_strip_degree": {
        k: (lambda xy, XY, s, m, k=k: _strip_degree(xy, XY, s, m, k))
        for k in ("complex r", "two-sided", "le1", "min", "no sigma")
    }
    | {
        f"fixed bound {t}": (lambda xy, XY, s, m, t=t: _strip_degree(xy, XY, s, m, t))
        for t in (1.1, 1.2, 1.3, 1.4)
    }
    | {
        f"level {q}": (lambda xy, XY, s, m, q=q: _strip_degree(xy, XY, s, m, q))
        for q in (0.9, 0.975)
    },
    "check_strips_for": {
        "natural log": lambda a, b, m: np.inf if b <= 0 else np.exp((m - a) / b),
        "a forgotten": lambda a, b, m: np.inf if b <= 0 else 10.0 ** (m / b),
        "exponent only": lambda a, b, m: np.inf if b <= 0 else (m - a) / b,
        "b <= 0 not handled": lambda a, b, m: 10.0 ** ((m - a) / b),
    },
}
