"""Checkers for lesson 01 (least squares: weights, σ0, propagation, error ellipses, Gauss-Newton).

Oracles: the propagation F C Fᵀ of a mean written out by hand; the weakest direction of a
point found by brute force (the standard deviation √(uᵀCu) in 200 001 directions u, C from a
central-difference Jacobian); redundancy numbers by re-solving; the second-order term of a
distance by central second differences; the line fit from the normal equations written out.
"""

from __future__ import annotations

import decimal
import math

import numpy as np

from ..adjust.engine import gauss_newton  # forbidden inside the student's line_fit
from ._common import CheckFailed, call, compare, exact_derivatives, own_work, rng_for, success

# --------------------------------------------------------------------- precision of a mean


def check_mean_sigma(fn) -> None:
    """``fn(sigma) -> (sigma_weighted, sigma_plain)``: σ (m) of the weighted mean (weights
    1/σ²) and of the plain mean of heights with a-priori σ (m), by propagation of variances.

    Oracle: σ_F = √(F C Fᵀ) with the row F of each mean and C = diag(σ²), written out here;
    the named mistakes are the plausible shortcuts (no root, weights 1/σ, σ̄/√n, RMS σ).
    """
    rng = rng_for("lesson01.check_mean_sigma")
    for n in (3, 5):
        sigma = np.sort(rng.uniform(0.005, 0.06, n))
        C = np.diag(sigma**2)
        F_w = (1 / sigma**2) / np.sum(1 / sigma**2)
        F_p = np.full(n, 1.0 / n)
        want = np.array([math.sqrt(F_w @ C @ F_w), math.sqrt(F_p @ C @ F_p)])
        got = call(fn, sigma.copy(), what="mean_sigma")
        if np.ndim(got) != 1 or len(got) != 2:
            raise CheckFailed("mean_sigma: return two numbers, (sigma_weighted, sigma_plain)")
        F_1 = (1 / sigma) / np.sum(1 / sigma)
        wrong_w = [
            ("this is the variance 1/Σ(1/σ²): take the square root", 1 / np.sum(1 / sigma**2)),
            ("the weights 1/σ: the weighted mean uses 1/σ², so F = (1/σ²)/Σ(1/σ²)",
             math.sqrt(F_1 @ C @ F_1)),
            ("σ/√n with the mean σ: that holds only for equal σ", np.mean(sigma) / math.sqrt(n)),
        ]  # fmt: skip
        wrong_p = [
            ("σ̄/√n with the mean σ: with unequal σ propagate F C Fᵀ, F = (1/n, …, 1/n)",
             np.mean(sigma) / math.sqrt(n)),
            ("this is the RMS of the σ, √(Σσ²/n): the mean divides by n, so √(Σσ²)/n",
             math.sqrt(np.mean(sigma**2))),
            ("this is the variance Σσ²/n²: take the square root", np.sum(sigma**2) / n**2),
        ]  # fmt: skip
        compare(f"σ of the weighted mean of {n} heights [m]", got[0], want[0], rtol=1e-9,
                wrong=wrong_w)  # fmt: skip
        compare(f"σ of the plain mean of {n} heights [m]", got[1], want[1], rtol=1e-9,
                wrong=wrong_p)  # fmt: skip
    success("σ of both means as F C Fᵀ gives them, for 3 and 5 heights")


# --------------------------------------------------------------------- the weakest direction


def _numeric_normal(stations, x, sigma):
    """N = JᵀPJ of distances from ``stations`` with a central-difference Jacobian."""
    h = 1e-5
    J = np.column_stack([
        (_distances(x + e, stations) - _distances(x - e, stations)) / (2 * h)
        for e in np.eye(2) * h
    ])  # fmt: skip
    return J.T @ (J / np.asarray(sigma, float)[:, None] ** 2)


def _worst_by_search(C):
    """The direction (unit vector) of largest √(uᵀCu) among 200 001 directions."""
    t = np.linspace(-np.pi / 2, np.pi / 2, 200_001)
    s = np.einsum(
        "in,ij,jn->n", np.stack([np.cos(t), np.sin(t)]), C, np.stack([np.cos(t), np.sin(t)])
    )
    k = int(np.argmax(s))
    return np.array([np.cos(t[k]), np.sin(t[k])])


def check_weakest_direction(fn) -> None:
    """``fn(stations, x, sigma) -> u``: the unit vector (either sign) along which a point x
    (m) fixed by distances from ``stations`` (k, 2) with σ (k,) m is worst determined.

    Oracle: σ in 200 001 directions from the inverse of a normal matrix built with a
    central-difference Jacobian."""
    rng = rng_for("lesson01.check_weakest_direction")
    for case in range(3):
        k = 4 + case % 2
        x = rng.uniform(-200, 200, 2)
        ang = rng.uniform(0, 2 * np.pi, k)
        stations = x + rng.uniform(300, 1500, k)[:, None] * np.column_stack(
            [np.cos(ang), np.sin(ang)]
        )
        sigma = rng.uniform(0.003, 0.03, k)
        N = _numeric_normal(stations, x, sigma)
        want = _worst_by_search(np.linalg.inv(N))
        got = np.asarray(
            call(fn, stations.copy(), x.copy(), sigma.copy(), what="weakest_direction"), float
        )
        if got.shape != (2,):
            raise CheckFailed(
                f"weakest_direction: return a unit vector of shape (2,), got shape {got.shape}"
            )
        norm = float(np.linalg.norm(got))
        if not np.isfinite(norm) or abs(norm - 1.0) > 1e-6:
            raise CheckFailed(
                f"weakest_direction: the vector has length {norm:.4g}; return a unit vector"
            )
        off = math.degrees(math.acos(min(1.0, abs(float(got @ want)))))
        if off <= 0.01:
            continue
        strong = np.array([-want[1], want[0]])
        unweighted = _worst_by_search(np.linalg.inv(_numeric_normal(stations, x, np.ones(k))))
        d = x - stations[int(np.argmax(sigma))]
        weak_ray = d / np.linalg.norm(d)
        why = "build N = Σ u_i u_iᵀ/σ_i² from the unit vectors u_i, and take the direction of C = N⁻¹'s largest σ"
        for text, w in (
            ("that is the BEST-determined direction: N's largest eigenvalue belongs to C = N⁻¹'s "
             "smallest; the weakest is the other eigenvector", strong),
            ("the σ are missing: weight each distance's row by 1/σ_i²", unweighted),
            ("that is the ray of the least precise distance: a direction is weak only if no "
             "precise ray covers it — ask N, not one station", weak_ray),
        ):  # fmt: skip
            if abs(float(got @ w)) > math.cos(math.radians(0.01)):
                why = text
                break
        raise CheckFailed(
            f"weakest_direction (case {case + 1}): off by {off:.2f}° from the direction of the largest σ: {why}",
            error=off / 0.01 * 1e-6, tolerance=1e-6,
        )  # fmt: skip
    success(
        "the direction of the largest σ (the ellipse's major axis), from N as a search over directions finds it"
    )


# --------------------------------------------------------------------- σ̂0 of a group


def _redundancy_by_perturbation(A: np.ndarray, l: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Redundancy numbers r_i = −∂v_i/∂l_i, each by moving l_i and solving again (lstsq of
    √P A): not the formula diag(I − A N⁻¹ Aᵀ P)."""
    sq = np.sqrt(p)

    def residuals(obs: np.ndarray) -> np.ndarray:
        x = np.linalg.lstsq(A * sq[:, None], obs * sq, rcond=None)[0]
        return A @ x - obs

    v0, eps = residuals(l), 1e-3
    r = np.empty(len(l))
    for i in range(len(l)):
        moved = l.copy()
        moved[i] += eps
        r[i] = -(residuals(moved)[i] - v0[i]) / eps
    return r


def _group_case(rng: np.random.Generator):
    """A quadratic fit to 30 observations in three groups whose true σ are 1, 2 and 4 times the
    claimed one, so the groups' σ̂0 differ."""
    t = np.sort(rng.uniform(-1.0, 1.0, 30))
    A = np.column_stack([np.ones_like(t), t, t**2])
    group = np.repeat([0, 1, 2], 10)[rng.permutation(30)]
    claimed = rng.uniform(0.5, 1.5, 30)
    l = A @ [2.0, -1.0, 0.5] + rng.normal(0.0, 1.0, 30) * claimed * np.array([1.0, 2.0, 4.0])[group]
    return A, l, claimed, group


def check_group_sigma0(fn) -> None:
    """``fn(A, l, sigma, group) -> s`` (k,): σ̂0 of each group g = 0 … k−1 of observations,
    sqrt(Σ_g p_i v_i² / Σ_g r_i) with the redundancy numbers r_i of the whole adjustment."""
    A, l, sigma, group = _group_case(rng_for("lesson01.check_group_sigma0"))
    p = 1.0 / sigma**2
    x = np.linalg.lstsq(A * np.sqrt(p)[:, None], l * np.sqrt(p), rcond=None)[0]
    v = A @ x - l
    r_i = _redundancy_by_perturbation(A, l, p)
    k = int(group.max()) + 1
    pvv = np.array([np.sum((p * v * v)[group == g]) for g in range(k)])
    n_g = np.array([np.sum(group == g) for g in range(k)], float)
    r_g = np.array([r_i[group == g].sum() for g in range(k)])
    want = np.sqrt(pvv / r_g)
    u = A.shape[1]
    wrong = [
        ("divided by the group's number of observations, not its share of the redundancy "
         "(Σ r_i over the group)", np.sqrt(pvv / n_g)),
        ("the redundancy split in proportion to the group's size, not by its redundancy numbers",
         np.sqrt(pvv / (n_g * (len(l) - u) / len(l)))),
        ("the weights are missing: v_i²/σ_i², not v_i²",
         np.sqrt(np.array([np.sum((v * v)[group == g]) for g in range(k)]) / r_g)),
        ("this is σ̂0², not σ̂0", want**2),
    ]  # fmt: skip
    got = call(fn, A.copy(), l.copy(), sigma.copy(), group.copy(), what="group_sigma0")
    compare("σ̂0 of the three groups", got, want, rtol=1e-6, wrong=wrong)
    success(
        f"σ̂0 per group {np.round(want, 3).tolist()} (true σ 1, 2, 4 × the claimed; "
        "redundancy numbers by re-solving with each observation moved)"
    )


# --------------------------------------------------------------------- the linearisation error


def _distances(x, stations):
    return np.linalg.norm(np.asarray(x, float)[None, :] - stations, axis=1)


def check_second_order(fn) -> None:
    """``fn(x, station, dx) -> e``: the second-order term (m) of the distance from ``station``
    to the point x + dx (m), s(x + dx) ≈ s(x) + uᵀdx + e.

    Oracle: half the second directional derivative of the distance along dx by central
    second differences of the checker's own distance."""
    rng = rng_for("lesson01.check_second_order")
    for _ in range(4):
        station = rng.uniform(-500, 500, 2)
        x = station + rng.uniform(200, 900) * np.array(
            [np.cos(a := rng.uniform(0, 6.3)), np.sin(a)]
        )
        dx = rng.normal(0.0, 30.0, 2)
        t = 1e-3
        s = lambda q, st=station: float(np.linalg.norm(q - st))  # noqa: E731
        want = 0.5 * (s(x + t * dx) - 2 * s(x) + s(x - t * dx)) / t**2
        got = call(fn, x.copy(), station.copy(), dx.copy(), what="second_order")
        try:
            got = float(got)
        except (TypeError, ValueError):
            raise CheckFailed(f"second_order: expected one number (m), got {got!r}") from None
        dist = s(x)
        u = (x - station) / dist
        along = float(u @ dx)
        perp2 = float(dx @ dx) - along**2
        compare(
            f"second-order term for |dx| = {np.linalg.norm(dx):.1f} m at s = {dist:.0f} m [m]",
            got, want, rtol=1e-5,
            wrong=[
                ("|dx|²/(2s): only the part of dx ACROSS the ray bends the distance; along the "
                 "ray s changes linearly", float(dx @ dx) / (2 * dist)),
                ("the factor 1/2 of the Taylor series is missing", perp2 / dist),
                ("the part ALONG the ray was used; the curvature comes from the part across it",
                 along**2 / (2 * dist)),
                ("the sign: s(x + dx) is never shorter than its linearisation (s is convex)",
                 -perp2 / (2 * dist)),
                ("this is the whole linearisation error s(x + dx) − s − uᵀdx, third and higher "
                 "orders included; the exercise is its second-order term",
                 s(x + dx) - dist - along),
            ],
        )  # fmt: skip
        exact_derivatives(
            "second-order term [m]", got, _second_difference_exact(x, station, dx), rtol=1e-11
        )
    success(
        "e = |dx_⊥|²/(2s): the linearisation error grows with the square of the offset across the ray"
    )


def _second_difference_exact(x: np.ndarray, station: np.ndarray, dx: np.ndarray) -> float:
    """½ d²s(x + t·dx)/dt² at t = 0 to about 1e-17: a central second difference (t = 1e-15)
    in 50-digit decimal arithmetic, where neither truncation nor cancellation is felt."""
    with decimal.localcontext() as ctx:
        ctx.prec = 50
        X, S, D = ([decimal.Decimal(float(v)) for v in a] for a in (x, station, dx))
        t = decimal.Decimal("1e-15")

        def s(k: int) -> decimal.Decimal:
            return sum(
                ((X[i] + k * t * D[i] - S[i]) ** 2 for i in range(2)), decimal.Decimal(0)
            ).sqrt()

        return float((s(1) - 2 * s(0) + s(-1)) / (2 * t * t))


# --------------------------------------------------------------------- the weighted line fit


def _line_wrong(X, l, sigma, mistake):
    """A line fit with one plausible mistake (the wrong answers the check names)."""
    A = np.column_stack([np.ones_like(X), X])
    p = {"no_weights": np.ones_like(sigma), "one_over_sigma": 1.0 / sigma}.get(
        mistake, 1.0 / sigma**2
    )
    N = A.T @ (p[:, None] * A)
    x = np.linalg.solve(N, A.T @ (p * l))
    v = A @ x - l
    r = len(l) if mistake == "divide_by_n" else len(l) - 2
    s0 = math.sqrt(float(v @ (p * v)) / r)
    Q = N if mistake == "Q_is_N" else np.linalg.inv(N)
    return x, (-v if mistake == "v_sign" else v), s0, Q


@own_work(gauss_newton=gauss_newton)
def check_line_fit(fn) -> None:
    """``fn(X, l, sigma) -> (xhat, v, sigma0, Q)``: the weighted straight line l ≈ a + b X
    (P = diag(1/σ²)), residuals v = A x̂ − l, σ̂0 = √(vᵀPv / (n − 2)) and Q = (AᵀPA)⁻¹."""
    rng = rng_for("lesson01.check_line_fit")
    X = np.sort(rng.uniform(-40.0, 60.0, 9))
    sigma = np.where(np.arange(9) % 3 == 0, 0.002, 0.007)
    l = 0.31 + 0.0042 * X + rng.normal(0.0, 1.0, 9) * sigma
    got = call(fn, X.copy(), l.copy(), sigma.copy(), what="line_fit")
    if not isinstance(got, tuple) or len(got) != 4:
        raise CheckFailed("line_fit: return the four results (xhat, v, sigma0, Q)")
    # oracle: a QR factorisation of √P A (no normal equations)
    A = np.column_stack([np.ones_like(X), X])
    Qr, Rr = np.linalg.qr(A / sigma[:, None])
    x = np.linalg.solve(Rr, Qr.T @ (l / sigma))
    v = A @ x - l
    Ri = np.linalg.inv(Rr)
    want = (x, v, math.sqrt(float(np.sum((v / sigma) ** 2)) / 7), Ri @ Ri.T)
    names = ("x̂ = (a, b)", "v [mm]", "σ̂0", "Q = N⁻¹")
    wrongs = {
        "no_weights": "the weights are forgotten (P = I): P = diag(1/σ²)",
        "one_over_sigma": "weights 1/σ instead of 1/σ²",
        "divide_by_n": "vᵀPv divided by n instead of the redundancy r = n − 2",
        "Q_is_N": "Q is the inverse of N = AᵀPA, not N itself",
        "v_sign": "the sign of v is wrong: v = A x̂ − l (computed − observed)",
    }
    for k, name in enumerate(names):
        compare(name, got[k], want[k], rtol=1e-8, wrong=[
            (text, _line_wrong(X, l, sigma, key)[k]) for key, text in wrongs.items()
        ])  # fmt: skip
    success("x̂, v, σ̂0 and Q agree with a QR solution of √P A x = √P l")
