"""Checkers for lesson 08, block triangulation.

Oracles: error-free simulated truth (a similarity, a conformal polynomial and a
logarithmic law with known parameters) and σ0 written out by hand; never the library's
``similarity_transform``, ``polynomial_adjust`` or ``fit_log_law``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from orientviz.exercises._common import CheckFailed, call, compare, relative_error, success


def _rodrigues(axis, angle: float) -> np.ndarray:
    """Rotation by ``angle`` (rad) about ``axis``, written out (not the library's)."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _similarity_cases(rng: np.random.Generator):
    """Two error-free cases: a hilly model and a flat one (all model z equal)."""
    x1 = rng.uniform(-100, 100, (6, 3)) * [1.0, 0.8, 0.15] + [0, 0, -150]
    x2 = np.column_stack([rng.uniform(-90, 90, 8), rng.uniform(-80, 80, 8), np.full(8, -152.0)])
    cases = []
    for x, axis, ang, s, t in (
        (x1, [0.3, -0.5, 0.8], 0.41, 7.3, [4520.0, 1870.0, 960.0]),
        (x2, [-0.2, 0.1, 1.0], 2.2, 9.85, [-310.0, 5400.0, 1520.0]),
    ):
        R = _rodrigues(axis, ang)
        cases.append((x, t + s * x @ R.T, s, R, np.array(t)))
    return cases


def _triple(out) -> tuple[float, np.ndarray, np.ndarray]:
    try:
        s_hat, R_hat, t_hat = out
        return float(s_hat), np.asarray(R_hat, float), np.asarray(t_hat, float)
    except (TypeError, ValueError):
        raise CheckFailed("return the three values (scale, R, t)") from None


def check_similarity(fn: Callable) -> None:
    """Check ``fn(x, X) -> (scale, R, t)`` with ``X = t + scale · R · x`` (closed form)."""
    rng = np.random.default_rng(807)  # the flat case makes numpy's SVD return a reflection
    for n_case, (x, X, s, R, t) in enumerate(_similarity_cases(rng), start=1):
        s_hat, R_hat, t_hat = _triple(call(fn, x.copy(), X.copy(), what="similarity_7"))
        what = "the flat model (all z equal)" if n_case == 2 else "a hilly model"
        if R_hat.shape == (3, 3) and np.linalg.det(R_hat) < 0:
            raise CheckFailed(
                f"R is a reflection (det R = {np.linalg.det(R_hat):+.3f}) for {what}: with "
                "coplanar points the SVD leaves the sign of the third axis open; multiply the "
                "last column of V by det(V Uᵀ)",
                error=relative_error(R_hat, R),
                tolerance=1e-8,
            )
        compare(f"scale ({what})", s_hat, s, rtol=1e-8, wrong=[("the inverse of the scale", 1 / s)])
        compare(
            f"R ({what})",
            R_hat,
            R,
            rtol=1e-8,
            wrong=[("R maps object → model: the transpose", R.T)],
        )
        compare(
            f"t ({what})", t_hat, t, rtol=1e-9, wrong=[("t = X̄ without − scale · R · x̄", X.mean(0))]
        )
    success("scale, R and t of two error-free models (one of them flat) recovered exactly")


def check_sigma0(fn: Callable) -> None:
    """Check ``fn(x, X, scale, R, t, sigma) -> σ̂0`` (unit weight) of a 7-parameter fit."""
    rng = np.random.default_rng(809)
    x, X, s, R, t = _similarity_cases(rng)[0]
    x = np.vstack([x, x[:3] * 0.7])
    sigma = 0.04
    X = t + s * x @ R.T + rng.normal(0, sigma, x.shape)
    n = len(x)
    v = t + s * x @ R.T - X
    want = float(np.sqrt(np.sum(v**2) / sigma**2 / (3 * n - 7)))
    got = call(fn, x, X, s, R, t, sigma, what="sigma0_similarity")
    compare(
        "σ̂0",
        got,
        want,
        rtol=1e-9,
        wrong=[
            (
                "divided by 3n instead of the redundancy 3n − 7",
                want * np.sqrt((3 * n - 7) / (3 * n)),
            ),
            ("divided by n − 7 (points, not coordinates)", want * np.sqrt((3 * n - 7) / (n - 7))),
            ("forgot to divide the residuals by σ (metres, not unit weight)", want * sigma),
            ("σ̂0² instead of σ̂0", want**2),
        ],
    )
    success(f"σ̂0 = {float(got):.4f} with r = 3n − 7 = {3 * n - 7}")


def check_conformal(fn: Callable) -> None:
    """Check ``fn(xy, XY, degree) -> c`` (complex, c[0] first) with X + iY = Σ c_k (x + iy)^k."""
    rng = np.random.default_rng(810)
    for degree in (2, 3):
        xy = rng.uniform(-1, 1, (12, 2)) * [5.0, 1.0]  # a strip: long in x, km
        c = rng.normal(size=degree + 1) + 1j * rng.normal(size=degree + 1)
        c[1] += 1.0  # mostly a scale and a rotation
        z = xy[:, 0] + 1j * xy[:, 1]
        Z = np.polyval(c[::-1], z)
        got = np.asarray(
            call(fn, xy.copy(), np.column_stack([Z.real, Z.imag]), degree, what="conformal_fit")
        )
        pair = lambda c_: np.column_stack([np.real(c_), np.imag(c_)])  # noqa: E731
        if got.shape != c.shape:
            raise CheckFailed(
                f"expected {degree + 1} complex coefficients for degree {degree}, got shape {got.shape}"
            )
        compare(
            f"coefficients (degree {degree}) as (real, imaginary)",
            pair(got),
            pair(c),
            rtol=1e-8,
            wrong=[
                ("the wrong order: give c0 (the shift) first", pair(c[::-1])),
                ("complex conjugates: the coordinates were paired as x − iy", pair(np.conj(c))),
            ],
        )
    success("the conformal polynomials of degree 2 and 3 recovered exactly")


def check_log_law(fn: Callable) -> None:
    """Check ``fn(n_s, mu) -> (a, b)`` for the law μ = a + b · log10(n_s)."""
    n_s = np.array([2, 3, 4, 6, 8, 12, 20])
    a, b = 0.62, 0.71
    out = call(fn, n_s.copy(), a + b * np.log10(n_s), what="log_law")
    compare(
        "(a, b)",
        out,
        [a, b],
        rtol=1e-9,
        wrong=[
            ("(a, b) swapped: return the constant a first", [b, a]),
            (
                "b/ln 10: the natural logarithm instead of log10",
                np.linalg.lstsq(
                    np.column_stack([np.ones(n_s.size), np.log(n_s)]),
                    a + b * np.log10(n_s),
                    rcond=None,
                )[0],
            ),
        ],
    )
    success(f"a = {a:.3f}, b = {b:.3f}: a straight line over log10 n_s")
