"""Checkers for lesson 01 (least squares: weights, σ0, error ellipses, the χ² test, Gauss-Newton).

Oracles: the weighted mean written out by hand; the error ellipse found by brute force
(the standard deviation sqrt(uᵀCu) in 200 001 directions u); the χ² quantiles of
``scipy.stats.chi2``; a Gauss-Newton step built from a central-difference Jacobian.
"""

from __future__ import annotations

import math

import numpy as np

from ..adjust.engine import gauss_newton  # forbidden inside the student's line_fit
from ._common import CheckFailed, call, compare, own_work, rng_for, success

# --------------------------------------------------------------------- weighted mean


def _wm_lstsq(h, sigma):
    """Oracle: the mean as the least-squares solution of √P·1·m = √P·h (numpy's lstsq)."""
    h = np.asarray(h, float)
    w = 1.0 / np.asarray(sigma, float)
    m = float(np.linalg.lstsq(w[:, None], w * h, rcond=None)[0][0])
    v = w * (m - h)
    return m, math.sqrt(float(v @ v) / (len(h) - 1))


def _wm_unweighted(h, sigma):
    m = float(np.mean(h))
    v = m - np.asarray(h, float)
    p = 1.0 / np.asarray(sigma, float) ** 2
    return m, math.sqrt(float(np.sum(p * v * v)) / (len(h) - 1))


def _wm_one_over_sigma(h, sigma):
    p = 1.0 / np.asarray(sigma, float)
    m = float(np.sum(p * h) / np.sum(p))
    v = m - np.asarray(h, float)
    return m, math.sqrt(float(np.sum(p * v * v)) / (len(h) - 1))


def _wm_divide_by_n(h, sigma):
    m, s0 = _wm_lstsq(h, sigma)
    return m, s0 * math.sqrt((len(h) - 1) / len(h))


def _wm_no_weights_in_sigma0(h, sigma):
    m, _ = _wm_lstsq(h, sigma)
    v = m - np.asarray(h, float)
    return m, math.sqrt(float(np.sum(v * v)) / (len(h) - 1))


def check_weighted_mean(fn) -> None:
    """``fn(h, sigma) -> (mean, sigma0)``: weighted mean of heights h (m) with a-priori
    σ (m), and σ̂0 = √(vᵀPv / r) with P = diag(1/σ²) (σ0 = 1 a priori, so σ̂0 has no unit)."""
    rng = rng_for("lesson01.check_weighted_mean")
    for n in (3, 5):
        sigma = rng.uniform(0.02, 0.12, n)
        h = 412.40 + rng.normal(0.0, 1.0, n) * sigma * 1.7
        got = call(fn, h.copy(), sigma.copy(), what="weighted_mean")
        if np.ndim(got) != 1 or len(got) != 2:
            raise CheckFailed("weighted_mean: return two numbers, (mean, sigma0)")
        want = _wm_lstsq(h, sigma)
        wrong = [
            ("the weights are forgotten (plain mean)", _wm_unweighted(h, sigma)),
            ("weights 1/σ instead of 1/σ²", _wm_one_over_sigma(h, sigma)),
            ("vᵀPv divided by n instead of the redundancy r = n − 1", _wm_divide_by_n(h, sigma)),
            ("σ0 from vᵀv without the weights", _wm_no_weights_in_sigma0(h, sigma)),
        ]
        compare(
            f"the mean of {n} heights [m]",
            got[0],
            want[0],
            rtol=1e-10,
            wrong=[(t, w[0]) for t, w in wrong],
        )
        compare(
            f"σ̂0 of {n} heights", got[1], want[1], rtol=1e-8, wrong=[(t, w[1]) for t, w in wrong]
        )
    success("weighted mean and σ̂0 agree with the hand formulas for 3 and 5 heights")


# --------------------------------------------------------------------- error ellipse


def _ellipse_brute(C):
    t = np.linspace(-np.pi / 2, np.pi / 2, 200_001)
    u = np.stack([np.cos(t), np.sin(t)])
    s = np.sqrt(np.einsum("in,ij,jn->n", u, C, u))
    i, j = int(np.argmax(s)), int(np.argmin(s))
    return float(s[i]), float(s[j]), float(t[i])


def _ellipse_variances(C):
    a, b, th = _ellipse_brute(C)
    return a * a, b * b, th


def _ellipse_minor_direction(C):
    a, b, th = _ellipse_brute(C)
    return a, b, th + np.pi / 2


def _ellipse_degrees(C):
    a, b, th = _ellipse_brute(C)
    return a, b, math.degrees(th)


def _ellipse_no_half(C):
    a, b, _ = _ellipse_brute(C)
    return a, b, math.atan2(2 * C[0, 1], C[0, 0] - C[1, 1])


def _angle_diff(t1, t2):
    """Difference of two axis directions (mod π), rad."""
    d = (t1 - t2 + np.pi / 2) % np.pi - np.pi / 2
    return abs(d)


def check_error_ellipse(fn) -> None:
    """``fn(C) -> (a, b, theta)``: semi-axes (a ≥ b, units of √C) and the angle of the
    major axis from the x axis (rad, counter-clockwise) of the standard ellipse of C."""
    rng = rng_for("lesson01.check_error_ellipse")
    for _ in range(3):
        sx, sy = rng.uniform(0.004, 0.02, 2)
        rho = rng.uniform(-0.8, 0.8)
        C = np.array([[sx * sx, rho * sx * sy], [rho * sx * sy, sy * sy]])
        got = tuple(float(g) for g in call(fn, C.copy(), what="ellipse"))
        a, b, th = _ellipse_brute(C)
        err_ab = float(np.max(np.abs(np.subtract(got[:2], (a, b))))) / a
        err_th = _angle_diff(got[2], th)
        if err_ab <= 1e-6 and err_th <= 1e-4:
            continue
        error = max(err_ab / 1e-6, err_th / 1e-4) * 1e-6
        for label, m in (
            (
                "variances instead of standard deviations (take the square roots)",
                _ellipse_variances,
            ),
            ("the angle of the minor axis, not the major one", _ellipse_minor_direction),
            ("the angle in degrees: give it in radians", _ellipse_degrees),
            ("2θ, not θ: tan 2θ = 2σxy/(σx² − σy²), halve the angle", _ellipse_no_half),
        ):
            w = m(C)
            if np.allclose(got[:2], w[:2], rtol=1e-6) and _angle_diff(got[2], w[2]) < 1e-4:
                raise CheckFailed(f"error ellipse of C = {np.round(C * 1e6, 2).tolist()} · 1e-6: {label}",
                                  error, 1e-6)  # fmt: skip
        raise CheckFailed(
            f"error ellipse of C = {np.round(C * 1e6, 2).tolist()} · 1e-6: expected a = {a:.6g}, "
            f"b = {b:.6g}, θ = {th:.5f} rad, got {got}",
            error,
            1e-6,
        )
    success("semi-axes and direction agree with a brute-force search over 200 001 directions")


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


# --------------------------------------------------------------------- Gauss-Newton step


def _distances(x, stations):
    return np.linalg.norm(np.asarray(x, float)[None, :] - stations, axis=1)


def _gn_step_numeric(x, stations, s, sigma):
    x = np.asarray(x, float)
    h = 1e-6
    J = np.empty((len(s), 2))
    for k in range(2):
        e = np.zeros(2)
        e[k] = h
        J[:, k] = (_distances(x + e, stations) - _distances(x - e, stations)) / (2 * h)
    P = np.diag(1.0 / np.asarray(sigma, float) ** 2)
    dx = np.linalg.solve(J.T @ P @ J, J.T @ P @ (s - _distances(x, stations)))
    return x + dx


def _gn_step(x, stations, s, sigma, sign, weights, unit):
    """A Gauss-Newton step with one plausible mistake switched on (the wrong answers)."""
    x = np.asarray(x, float)
    f = _distances(x, stations)
    J = (x[None, :] - stations) / (f[:, None] if unit else 1.0)
    p = 1.0 / np.asarray(sigma, float) ** 2 if weights else np.ones(len(s))
    dx = np.linalg.solve(J.T @ (p[:, None] * J), J.T @ (p * (s - f)))
    return x + sign * dx


def check_gauss_newton_step(fn) -> None:
    """``fn(x, stations, s, sigma) -> x_new``: one Gauss-Newton step of a 2-D point
    (m) from measured distances s (m, σ in m) to known stations (k, 2)."""
    rng = rng_for("lesson01.check_gauss_newton_step")
    stations = np.array([[0.0, 0.0], [820.0, 40.0], [300.0, 910.0], [-250.0, 500.0]])
    truth = np.array([310.0, 360.0])
    sigma = np.array([0.004, 0.012, 0.006, 0.02])
    s = _distances(truth, stations) + rng.normal(0, 1, 4) * sigma
    x = truth + np.array([7.0, -4.0])
    got = np.asarray(
        call(fn, x.copy(), stations.copy(), s.copy(), sigma.copy(), what="gn_step"), float
    )
    want = _gn_step_numeric(x, stations, s, sigma)
    wrong = [
        ("the correction is subtracted: N Δx = JᵀP(l − f(x)), then x + Δx",
         _gn_step(x, stations, s, sigma, -1.0, True, True)),
        ("the weights are forgotten", _gn_step(x, stations, s, sigma, 1.0, False, True)),
        ("the Jacobian rows are not unit vectors: ∂s_i/∂X = (X − X_i)/s_i",
         _gn_step(x, stations, s, sigma, 1.0, True, False)),
    ]  # fmt: skip
    # 1e-9 of the coordinates ≈ 0.4 µm: the numerical Jacobian's own error is far smaller
    compare("the point after one step [m]", got, want, rtol=1e-9, wrong=wrong)
    success(
        f"one step from 8 m off lands {np.linalg.norm(got - truth) * 1000:.1f} mm from the truth, "
        "as a step with a numerical Jacobian does"
    )


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
