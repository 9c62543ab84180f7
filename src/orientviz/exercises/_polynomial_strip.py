"""Checker for lesson 08's polynomial method on one strip.

The student corrects the coordinates of one strip (already brought near the object frame by a
similarity) by a conformal polynomial in planimetry and a polynomial in height, each fitted to
the strip's control points by least squares::

    X + iY = x + iy + Σ_{k=0}^{d_xy} c_k w^k,                  w = (x + iy − centre) / 1000 m
    Z      = z + Σ_{k=0}^{d_z} a_k u^k + v Σ_{k=0}^{d_z − 1} e_k u^k,   u + iv = w

Oracles: (1) error-free control made from the strip coordinates by known coefficients of
exactly this form — every point of the strip must come back exactly (a wrong degree or a
missing term cannot); (2) noisy control — the checker's own fit with the real rows of
Ackermann's Table 1 (a0 + a1 x − b1 y + …, the complex product written out), centred on a
point of its own choosing, compared at every point of the strip.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from ..polynomial import polynomial_adjust  # forbidden inside the student's function
from ._common import call, compare, own_work, rng_for, success

F64 = NDArray[np.float64]

__all__ = ["check_strip_polynomial"]


def _strip(rng: np.random.Generator, n: int) -> F64:
    """Strip coordinates near the object frame: 7.5 km × 1.4 km, heights 80–260 m."""
    x0 = rng.uniform(-2000.0, 2000.0, 2)
    return np.column_stack(
        [
            x0[0] + rng.uniform(0.0, 7500.0, n),
            x0[1] + rng.uniform(-700.0, 700.0, n),
            rng.uniform(80.0, 260.0, n),
        ]
    )


def _real_rows(x: F64, centre: F64, dxy: int, dz: int) -> tuple[F64, F64, F64]:
    """Real design rows (Table 1 written out) of X, of Y and of Z for the coefficients."""
    u, v = (x[:, 0] - centre[0]) / 1000.0, (x[:, 1] - centre[1]) / 1000.0
    # Re and Im of w^k by the recursion w^k = w^(k−1) (u + iv), no complex arithmetic
    re, im = [np.ones_like(u)], [np.zeros_like(u)]
    for _ in range(dxy):
        re.append(re[-1] * u - im[-1] * v)
        im.append(re[-2] * v + im[-1] * u)
    p, q = np.column_stack(re), np.column_stack(im)
    AX = np.hstack([p, -q])  # X: Σ a_k Re(w^k) − b_k Im(w^k)
    AY = np.hstack([q, p])  # Y: Σ a_k Im(w^k) + b_k Re(w^k)
    AZ = np.column_stack([u**k for k in range(dz + 1)] + [v * u**k for k in range(dz)])
    return AX, AY, AZ


def _real_fit(x: F64, X: F64, dxy: int, dz: int, centre: F64, how: str) -> F64:
    """The checker's fit (``how`` = "right") or a named wrong variant of it."""
    AX, AY, AZ = _real_rows(x, centre, dxy, dz)
    plan = ~np.isnan(X[:, 0]) & ~np.isnan(X[:, 1])
    height = ~np.isnan(X[:, 2])
    if how == "full control only":
        plan = height = plan & height
    if how == "degree too low":
        AX, AY, _ = _real_rows(x, centre, dxy - 1, dz)
    if how == "no cross tilt":
        AZ = AZ[:, : dz + 1]
    u, v = (x[:, 0] - centre[0]) / 1000.0, (x[:, 1] - centre[1]) / 1000.0
    if how == "cross tilt to d":
        AZ = np.column_stack([AZ, v * u**dz])
    if how == "cross tilt too low" and dz >= 2:
        AZ = np.delete(AZ, -1, axis=1)
    A = np.vstack([AX[plan], AY[plan]])
    sign = -1.0 if how == "sign" else 1.0
    l = sign * np.concatenate([X[plan, 0] - x[plan, 0], X[plan, 1] - x[plan, 1]])
    c = np.linalg.lstsq(A, l, rcond=None)[0]
    e = np.linalg.lstsq(AZ[height], sign * (X[height, 2] - x[height, 2]), rcond=None)[0]
    return x + np.column_stack([AX @ c, AY @ c, AZ @ e])


def _control(rng: np.random.Generator, n: int, n_ctrl: int) -> tuple[F64, F64]:
    """Which points carry control: plan and height masks (some plan-only, some height-only)."""
    idx = rng.permutation(n)
    plan = np.zeros(n, bool)
    height = np.zeros(n, bool)
    plan[idx[:n_ctrl]] = True
    height[idx[3 : n_ctrl + 3]] = True  # three plan-only, three height-only points
    return plan, height


@own_work(polynomial_adjust=polynomial_adjust)
def check_strip_polynomial(fn: Callable[[F64, F64, int, int], F64]) -> None:
    """``fn(x, X, degree_xy, degree_z) -> (n, 3)``: x (n, 3) strip coordinates [m], X (n, 3)
    control [m] with NaN where a point has no control in that coordinate; the corrected
    coordinates of all n points."""
    for salt, (dxy, dz, n, n_ctrl) in enumerate(((3, 3, 40, 12), (2, 2, 30, 10))):
        rng = rng_for("lesson08.check_strip_polynomial", salt)
        x = _strip(rng, n)
        # (1) error-free: the truth is the strip corrected by known coefficients of the model
        centre = x[:, :2].mean(axis=0) + rng.uniform(-300.0, 300.0, 2)
        AX, AY, AZ = _real_rows(x, centre, dxy, dz)
        c = rng.normal(0.0, 1.0, 2 * (dxy + 1)) * np.r_[[3.0, 3.0], [0.4] * (2 * dxy)]
        e = rng.normal(0.0, 1.0, AZ.shape[1]) * np.r_[2.0, [0.3] * (AZ.shape[1] - 1)]
        truth = x + np.column_stack([AX @ c, AY @ c, AZ @ e])
        plan, height = _control(rng, n, n_ctrl)
        X = np.full_like(truth, np.nan)
        X[plan, :2], X[height, 2] = truth[plan, :2], truth[height, 2]
        got = call(fn, x.copy(), X.copy(), dxy, dz, what="strip_polynomial")
        wrong = [
            (
                "the planimetric polynomial is one degree too low: k = 0 … d are d + 1 "
                "complex coefficients",
                _real_fit(x, X, dxy, dz, centre, "degree too low"),
            ),
            (
                "the height polynomial lacks the cross tilt v·u^k (k = 0 … d − 1): a strip "
                "also tilts across its flight line",
                _real_fit(x, X, dxy, dz, centre, "no cross tilt"),
            ),
            (
                "the correction has the wrong sign: fit X − x (control minus strip) and add "
                "it to the strip coordinates",
                _real_fit(x, X, dxy, dz, centre, "sign"),
            ),
            (
                "the cross tilt v·u^k runs to k = d_z − 1 (one degree below the bend), not to "
                "d_z − 2",
                _real_fit(x, X, dxy, dz, centre, "cross tilt too low"),
            ),
        ]
        compare(
            f"strip {salt + 1} (degrees {dxy}/{dz}), error-free control: all {n} points [m]",
            got,
            truth,
            rtol=1e-6,
            scale=1.0,
            wrong=wrong,
        )
        # (2) noisy control: the checker's real-valued fit, centred elsewhere
        noisy = X + rng.normal(0.0, 0.05, X.shape)
        got = call(fn, x.copy(), noisy.copy(), dxy, dz, what="strip_polynomial")
        want = _real_fit(x, noisy, dxy, dz, x[:, :2].min(axis=0), "right")
        wrong = [
            (
                "a point with plan control only (or height control only) still counts for "
                "planimetry (for height)",
                _real_fit(x, noisy, dxy, dz, centre, "full control only"),
            ),
            (
                "the cross tilt v·u^k runs to k = d_z − 1, one degree below the bend: with "
                "k = d_z it takes up noise of the control",
                _real_fit(x, noisy, dxy, dz, centre, "cross tilt to d"),
            ),
        ]
        compare(
            f"strip {salt + 1}, control with 5 cm noise: all {n} points [m]",
            got,
            want,
            rtol=1e-6,
            scale=1.0,
            wrong=wrong,
        )
    success(
        "two strips: error-free control gives back every point, noisy control the "
        "least-squares polynomials (Table 1's real rows)"
    )
