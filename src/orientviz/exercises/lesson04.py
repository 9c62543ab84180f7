"""Checkers for lesson 04, space resection and forward intersection.

Oracles (never :func:`orientviz.orientation.resection.resection` or
:func:`orientviz.orientation.intersection.intersect_points`):

* the resection: :func:`scipy.optimize.least_squares` on the checker's own collinearity
  residuals (an independent minimiser), and error-free simulated truth;
* two rays: a scene built around a known common perpendicular, so the midpoint is known;
* partial derivatives: central differences of the checker's own collinearity;
* the normal-case precision: the covariance of a two-ray intersection from numerical
  derivatives;
* ρ(X0, φ) of a vertical image: the design by central differences, the cofactors from its QR
  decomposition, not from the normal equations;
* the best extra control point: a search over every candidate, each σ from the inverse of
  normal equations built with numerical derivatives.

Units: object space m, image mm, angles rad, σ of image coordinates mm.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from ..camera import project  # forbidden in design_X0 (own_work): the stand-in differentiates it
from ..orientation.intersection import intersect_points, intersect_rays  # forbidden inside the
from ..orientation.resection import resection  # student's functions (own_work), never an oracle
from ._common import (
    CheckFailed,
    call,
    compare,
    complex_step,
    exact_derivatives,
    own_work,
    rng_for,
    success,
)
from .lesson02 import _rodrigues_opk

__all__ = [
    "check_best_extra_point",
    "check_design_X0",
    "check_resection",
    "check_rho_x0_phi",
    "check_sigma_X",
    "check_two_rays",
]

F64 = NDArray[np.float64]


def _R(angles_rad: F64) -> F64:
    return _rodrigues_opk(*angles_rad, unit=1.0)


def _project(X: F64, X0: F64, R: F64, c: float) -> F64:
    uvw = (X - X0) @ R
    return -c * uvw[:, :2] / uvw[:, 2:]


def _scene(rng: np.random.Generator, n: int = 9) -> tuple[F64, F64, F64, F64]:
    """Control points, true parameters (X0, angles in rad) and error-free image points."""
    X = np.column_stack(
        [rng.uniform(-900, 900, n), rng.uniform(-900, 900, n), rng.uniform(0, 150, n)]
    )
    p = np.array([35.0, -22.0, 1500.0, *rng.uniform(-0.04, 0.04, 2), rng.uniform(-3, 3)])
    xy = _project(X, p[:3], _R(p[3:]), 152.7)
    return X, p, xy, np.array(152.7)


def _minimise(fun: Callable[[F64], F64], start: F64) -> F64:
    """The oracle's minimiser: scipy's trust-region least squares, run to machine precision."""
    scale = np.array([1, 1, 1, 1e-3, 1e-3, 1e-3])
    return least_squares(fun, start, x_scale=scale, xtol=1e-15, ftol=1e-15, gtol=1e-15).x


def _stopped_early(p: F64, start: F64, truth: F64, X: F64, xy: F64, c: float) -> str | None:
    """Name an answer that is the start after 0, 1 or 2 Gauss-Newton steps (error-free points).

    The oracle's steps use central differences of the checker's own collinearity; an answer
    within 1e-3 of that step's distance from the truth is taken to be that step.
    """
    if p.shape != (6,) or not np.all(np.isfinite(p)):
        return None

    def f(q: F64) -> F64:
        return _project(X, q[:3], _R(q[3:]), c).ravel()

    q = start.copy()
    for k in range(3):
        off = float(np.abs(q - truth).max())
        if float(np.abs(p - q).max()) <= 1e-3 * off:
            return (
                "this is the start itself — add each correction dx to p"
                if k == 0
                else f"this is the start after {k} Gauss-Newton step{'s' if k > 1 else ''} "
                f"(still {np.abs(q[:3] - truth[:3]).max():.3g} m from the truth) — you stopped "
                "too early"
            )
        A = np.column_stack([(f(q + h) - f(q - h)) / 2e-6 for h in np.eye(6) * 1e-6])
        q = q + np.linalg.lstsq(A, xy.ravel() - f(q), rcond=None)[0]
    return None


@own_work(resection=resection)
def check_resection(resection_gn: Callable[..., tuple[F64, float]]) -> None:
    """``resection_gn(xy, X, c, sigma, p0)`` must return (p̂, σ̂0), p = (X0, Y0, Z0, ω, φ, κ) in m, rad."""
    rng = rng_for("lesson04.check_resection")
    X, truth, xy, c = _scene(rng)
    start = truth + np.array([40.0, -30.0, 25.0, 0.02, -0.015, 0.03])
    # 1. error-free image points: the truth must come back, with σ̂0 ≈ 0
    out = call(resection_gn, xy, X, float(c), 0.005, start.copy(), what="resection_gn")
    p, s0 = np.asarray(out[0], dtype=float), float(out[1])
    try:
        compare("X0, Y0, Z0 [m] from error-free points", p[:3], truth[:3], rtol=1e-6, scale=1.0)
        compare("ω, φ, κ [rad] from error-free points", p[3:], truth[3:], rtol=1e-9, scale=1.0)
    except CheckFailed as exc:
        stopped = _stopped_early(p, start, truth, X, xy, float(c))
        hint = "\n  (the start was 40 m and ~1 gon off: iterate until the corrections are tiny, and add dx to p)"
        raise CheckFailed(
            (f"✗ (X0, Y0, Z0, ω, φ, κ) from error-free points: {stopped}; iterate until the "
             "corrections are tiny (e.g. < 1e-6 m and 1e-9 rad)" if stopped else str(exc) + hint),
            exc.error,
            exc.tolerance,
        ) from None  # fmt: skip
    # 2. noisy, unequal σ: p̂ and σ̂0 against scipy's minimiser of the weighted residuals
    sigma = np.where(np.arange(len(X)) % 2 == 0, 0.003, 0.009)[:, None] * np.ones((1, 2))
    noisy = xy + rng.normal(0.0, 1.0, xy.shape) * sigma

    def weighted(q: F64) -> F64:
        return ((_project(X, q[:3], _R(q[3:]), float(c)) - noisy) / sigma).ravel()

    ref = _minimise(weighted, start)
    r = noisy.size - 6
    s0_ref = float(np.sqrt(np.sum(weighted(ref) ** 2) / r))
    plain = _minimise(lambda q: weighted(q) * sigma.ravel(), start)
    s0_unweighted = float(np.sqrt(np.sum((weighted(plain) * sigma.ravel()) ** 2) / r))
    out = call(resection_gn, noisy, X, float(c), sigma, start.copy(), what="resection_gn")
    p, s0 = np.asarray(out[0], dtype=float), float(out[1])
    wrong = [
        ("σ̂0 without weights (in mm): weight each residual with 1/σ²", s0_unweighted),
        ("σ̂0 divided by n, not by the redundancy r = 2n − 6", s0_ref * np.sqrt(r / noisy.size)),
    ]
    compare("σ̂0 (noisy points, unequal σ)", s0, s0_ref, rtol=1e-4, wrong=wrong)
    compare("X0, Y0, Z0 [m] (noisy points, unequal σ)", p[:3], ref[:3], rtol=1e-5, scale=1.0)
    compare("ω, φ, κ [rad] (noisy points, unequal σ)", p[3:], ref[3:], rtol=1e-8, scale=1.0)
    success(
        f"resection: the truth from error-free points; σ̂0 = {s0:.3f} as an independent minimiser finds it"
    )


@own_work(intersect_rays=intersect_rays)
def check_two_rays(intersect_two_rays: Callable[[F64, F64, F64, F64], F64]) -> None:
    """``intersect_two_rays(X01, d1, X02, d2)`` must return the midpoint of the shortest segment (3,)."""
    rng = rng_for("lesson04.check_two_rays")
    for _ in range(3):
        P = rng.uniform(-500, 500, 3) + [0, 0, 200]
        d1, d2 = rng.normal(size=3), rng.normal(size=3)
        d1[2], d2[2] = -abs(d1[2]) - 1, -abs(d2[2]) - 1
        n = np.cross(d1, d2)
        n /= np.linalg.norm(n)
        h = rng.uniform(0.05, 0.5)  # half the gap between the rays, m
        Q1, Q2 = P + h * n, P - h * n
        X01, X02 = Q1 - rng.uniform(800, 1500) * d1, Q2 - rng.uniform(800, 1500) * d2
        got = call(
            intersect_two_rays,
            X01.copy(),
            d1 * 3.0,
            X02.copy(),
            d2 * 0.5,
            what="intersect_two_rays",
        )
        a1, a2 = d1 * 3.0, d2 * 0.5  # the directions as handed in
        bb = X02 - X01
        l1, l2 = np.linalg.solve(
            np.array([[a1 @ a1, a1 @ a2], [a1 @ a2, a2 @ a2]]), [a1 @ bb, -a2 @ bb]
        )
        wrong = [
            ("this is the point on ray 1, not the midpoint", Q1),
            ("this is the point on ray 2, not the midpoint", Q2),
            ("the sign of the cross term d1ᵀd2 in the 2 × 2 system is wrong (it is −d1ᵀd2)",
             (X01 + l1 * a1 + X02 + l2 * a2) / 2),
        ]  # fmt: skip
        compare("midpoint [m]", got, P, rtol=1e-9, scale=1.0, wrong=wrong)
    success(
        "two rays: the midpoint of their common perpendicular (direction lengths do not matter)"
    )


def _numeric_design(X: F64, X0: F64, R: F64, c: float, h: float = 1e-3) -> F64:
    cols = []
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        cols.append(((_project(X, X0 + e, R, c) - _project(X, X0 - e, R, c)) / (2 * h)).ravel())
    return np.column_stack(cols)


@own_work(
    "the exercise is the analytic derivatives; central differences of the library's projection "
    "(the stand-in numeric_X0 above) are what the cell after the check compares them with",
    project=project,
)
def check_design_X0(design_X0: Callable[[F64, F64, F64, float], F64]) -> None:
    """``design_X0(X, X0, R, c)`` must return ∂(x1, y1, x2, y2, …)/∂(X0, Y0, Z0), shape (2n, 3), mm/m.

    The answer may not call the library's ``project`` (the lesson's numerical stand-in does)."""
    rng = rng_for("lesson04.check_design_X0")
    X, p, _, c = _scene(rng, 5)
    R = _R(p[3:] * 20)  # a strongly tilted image, so that R and Rᵀ differ clearly
    X0 = p[:3]
    truth = _numeric_design(X, X0, R, float(c))
    got = call(design_X0, X, X0, R, float(c), what="design_X0")
    order = np.vstack([truth[0::2], truth[1::2]])
    wrong = [
        ("these are the derivatives by the point X, not by X0 (sign)", -truth),
        ("the rows must alternate x1, y1, x2, y2, …", order),
        ("the columns are by R instead of Rᵀ", _numeric_design(X, X0, R.T, float(c))),
    ]
    compare("∂(x, y)/∂X0 [mm/m]", got, truth, rtol=1e-6, wrong=wrong)
    exact = complex_step(lambda q: _project(X, q, R, float(c)).ravel(), X0)
    exact_derivatives("∂(x, y)/∂X0", got, exact)
    success(
        "design matrix for X0, Y0, Z0 agrees with numerical derivatives and, to round-off, "
        "with exact ones"
    )


def _normal_case_cov(t: float, B: float, H: float, c: float, sx: float) -> F64:
    """Covariance (m²) of a ground point at X = t·B, Y = 0, Z = 0 intersected from two vertical
    images at (0, 0, H) and (B, 0, H), all four image coordinates with σ = sx (mm); by
    numerical derivatives of the checker's own projection."""
    P = np.array([[t * B, 0.0, 0.0]])
    A = []
    for X0 in (np.array([0.0, 0, H]), np.array([B, 0, H])):
        cols = []
        for k in range(3):
            e = np.zeros(3)
            e[k] = 1e-3
            cols.append(
                (
                    (_project(P + e, X0, np.eye(3), c) - _project(P - e, X0, np.eye(3), c)) / 2e-3
                ).ravel()
            )
        A.append(np.column_stack(cols))
    A = np.vstack(A) / sx
    return np.linalg.inv(A.T @ A)


def check_sigma_X(sigma_X: Callable[[float, float, float, float, float], float]) -> None:
    """``sigma_X(x1, B, H, c, sigma_x)`` (mm, m, m, mm, mm): σ [m] of the ground coordinate X
    along the base of a point on the base's ground track (Y = 0, flat ground) that the left
    image of a normal-case pair sees at x1."""
    rng = rng_for("lesson04.check_sigma_X")
    ts = (0.5, 0.0, 0.83, -0.35, 1.0, 1.4)
    for t in ts:
        B, H, c, sx = (
            rng.uniform(300, 900),
            rng.uniform(800, 3000),
            152.7,
            rng.uniform(0.003, 0.008),
        )
        x1 = c * t * B / H
        truth = float(np.sqrt(_normal_case_cov(t, B, H, c, sx)[0, 0]))
        with own_work(
            "the exercise is the derivation; the library's adjusted intersection skips it",
            intersect_points=intersect_points,
            intersect_rays=intersect_rays,
        ):
            got = call(sigma_X, x1, B, H, c, sx, what="sigma_X")
        g = H / c * sx  # the ground size of σ_x
        sz = np.sqrt(2.0) * H / B * H / c * sx
        wrong = [
            ("this is σ_X of a point midway between the images (the ground size of σ_x over √2) "
             "for every point: X depends on the position along the base", g / np.sqrt(2.0)),
            ("X = x' (H − Z)/c with x' and Z taken as independent: they are not — Z comes from "
             "the parallax p = x' − x'', which contains x' itself (the errors partly cancel)",
             float(np.hypot(g, x1 / c * sz))),
            ("(H/c)·σ_x: this is the left image alone (X is intersected from both rays, x'' "
             "enters through the parallax), or the parts of dx' and dx'' added instead of their "
             "squares (they are independent)", g),
            ("the square root is missing", truth**2),
            ("σ_x must be in mm here (5 µm = 0.005 mm), not µm", truth * 1000.0),
        ]  # fmt: skip
        compare(f"σ_X at {t:.2f} of the base (B = {B:.0f} m, H = {H:.0f} m) [m]", got, truth,
                rtol=1e-6, wrong=wrong)  # fmt: skip
    success(
        "σ_X along the base agrees with the covariance of the two-ray intersection (six points, "
        "inside and outside the base)"
    )


def _cofactor_std(X: F64, p: F64, c: float, sigma: F64) -> F64:
    """A-priori σ of (X0, Y0, Z0, ω, φ, κ) from the points X with image σ (n,), by numerical derivatives."""

    def f(q: F64) -> F64:
        return _project(X, q[:3], _R(q[3:]), c).ravel()

    steps = np.array([1e-3, 1e-3, 1e-3, 1e-7, 1e-7, 1e-7])
    A = np.column_stack([(f(p + h) - f(p - h)) / (2 * h[k]) for k, h in enumerate(np.diag(steps))])
    P = np.repeat(1.0 / np.asarray(sigma, dtype=float) ** 2, 2)
    return np.sqrt(np.diag(np.linalg.inv(A.T @ (P[:, None] * A))))


def _extra_point_scene(rng: np.random.Generator) -> tuple:
    """Six control points, 40 candidates with unequal σ (3 or 12 µm), an orientation near vertical."""
    X, p, xy, c = _scene(rng, 6)
    X[:, :2] *= 0.5  # the control clustered in the middle of the image: a weak resection
    xy = _project(X, p[:3], _R(p[3:]), float(c))
    Xn = np.column_stack(
        [rng.uniform(-1100, 1100, 40), rng.uniform(-1100, 1100, 40), rng.uniform(0, 150, 40)]
    )
    xyn = _project(Xn, p[:3], _R(p[3:]), float(c))
    sn = np.where(rng.uniform(size=40) < 0.5, 0.003, 0.012)
    return xy, X, np.full(len(X), 0.005), float(c), p, xyn, Xn, sn


@own_work(resection=resection)
def check_best_extra_point(best_extra_point: Callable[..., int]) -> None:
    """``best_extra_point(xy, X, sigma, c, p, xy_new, X_new, sigma_new, k)`` must return the index of
    the candidate point whose addition makes the a-priori σ of parameter ``k`` of the resection
    smallest (p = X0, Y0, Z0 in m, ω, φ, κ in rad; σ of the image coordinates in mm, one per point)."""
    rng = rng_for("lesson04.check_best_extra_point")
    for k, name in ((1, "Y0"), (0, "X0")):
        xy, X, s, c, p, xyn, Xn, sn = _extra_point_scene(rng)
        sig = np.array(
            [_cofactor_std(np.vstack([X, Xn[j]]), p, c, np.r_[s, sn[j]])[k] for j in range(len(Xn))]
        )
        plain = np.array(
            [_cofactor_std(np.vstack([X, Xn[j]]), p, c, np.r_[s, 0.005])[k] for j in range(len(Xn))]
        )
        other = np.array(
            [
                _cofactor_std(np.vstack([X, Xn[j]]), p, c, np.r_[s, sn[j]])[1 - k]
                for j in range(len(Xn))
            ]
        )
        out = call(
            best_extra_point, xy.copy(), X.copy(), s.copy(), c, p.copy(), xyn.copy(), Xn.copy(),
            sn.copy(), k, what="best_extra_point",
        )  # fmt: skip
        try:
            j = int(np.asarray(out).item())
        except (TypeError, ValueError):
            raise CheckFailed(
                f"best_extra_point: expected one index (an int), got {out!r}."
            ) from None
        if not 0 <= j < len(Xn):
            raise CheckFailed(
                f"best_extra_point: index {j} is not one of the {len(Xn)} candidates."
            )
        best = int(np.argmin(sig))
        if j == best:
            continue
        notes = {
            int(np.argmax(np.hypot(*xyn.T))): "this is the candidate farthest from the image "
            "centre — far out helps, but its σ and its direction matter too",
            int(np.argmin(plain)): "this is the best candidate if every point had the same σ: "
            "a forgotten weight (the candidates are measured with 3 µm or 12 µm)",
            int(np.argmin(other)): f"this is the best candidate for {'X0' if k == 1 else 'Y0'}, "
            f"not for {name} (parameter k = {k})",
            int(np.argmax(sig)): "this is the worst candidate, not the best (argmax for argmin?)",
        }
        why = notes.get(j, "")
        raise CheckFailed(
            f"best_extra_point (k = {k}, {name}): your candidate {j} gives σ {sig[j]:.4f} m, "
            f"candidate {best} gives {sig[best]:.4f} m" + (f" — {why}." if why else "."),
            error=float(sig[j] / sig[best] - 1.0),
            tolerance=1e-9,
        )
    success(
        "best_extra_point: the candidate that shrinks the chosen σ most, as a search over all of them finds"
    )


def check_rho_x0_phi(fn: Callable[[F64, float, float], float]) -> None:
    """``fn(xy, c, H) -> ρ``: the correlation of X0 and φ when only these two are estimated
    from the x and y image coordinates ``xy`` (n, 2) mm of flat control (Z = 0) seen by a
    vertical image (R = I) from the height H (m), all coordinates with one σ.

    Oracle: the design matrix by central differences of the checker's own collinearity,
    the cofactors from the QR decomposition of it (not the normal equations).
    """
    rng = rng_for("lesson04.check_rho_x0_phi")
    for spread in (110.0, 40.0):
        c, H = 152.7, float(rng.uniform(1200.0, 1800.0))
        xy = rng.uniform(-spread, spread, (8, 2))
        X = np.column_stack([xy * H / c, np.zeros(8)])  # the control on the ground, Z = 0
        X0 = np.array([0.0, 0.0, H])

        def f(q: F64, X: F64 = X, X0: F64 = X0, c: float = c) -> F64:  # q = (X0, φ)
            return _project(X, X0 + [q[0], 0.0, 0.0], _R(np.array([0.0, q[1], 0.0])), c).ravel()

        h = np.array([1e-3, 1e-7])
        A = np.column_stack([(f(e) - f(-e)) / (2 * e[k]) for k, e in enumerate(np.diag(h))])
        Rq = np.linalg.qr(A, mode="r")
        Q = np.linalg.inv(Rq.T @ Rq)
        rho = Q[0, 1] / np.sqrt(Q[0, 0] * Q[1, 1])
        Ax = A[0::2]
        Qx = np.linalg.inv(Ax.T @ Ax)
        N = A.T @ A
        wrong = [
            ("the sign is reversed: one column of the design has the wrong sign (a derivative "
             "by X0 or by φ), or this is the correlation of the normal matrix N instead of its "
             "inverse Q = N⁻¹ (for two unknowns the two differ only in sign)",
             N[0, 1] / np.sqrt(N[0, 0] * N[1, 1])),
            ("this is the cofactor Q(X0, φ), not divided by √(Q(X0, X0) Q(φ, φ))", Q[0, 1]),
            ("only the x equations: a tilt φ also moves y by x·y/c·dφ",
             Qx[0, 1] / np.sqrt(Qx[0, 0] * Qx[1, 1])),
        ]  # fmt: skip
        got = float(call(fn, xy.copy(), c, H, what="rho_x0_phi"))
        compare(f"ρ(X0, φ) for control within ±{spread:.0f} mm", got, rho, rtol=1e-6, scale=1.0,
                wrong=wrong)  # fmt: skip
    success("ρ(X0, φ) of a vertical image, for control spread wide and narrow")
