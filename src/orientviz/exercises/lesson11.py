"""Checkers for lesson 11, systematic image errors and self-calibration.

Oracles: error-free simulated distortion with known coefficients (for the real camera's
exercise a C4040Z-like sensor and the backward model), the one-parameter adjustment from the
normal matrix recovered by inverting Q, scipy's normal quantile, and a
QR projection for the share of a field that a parameter set describes — never the
library's ``self_calibrate``, ``analyse`` or ``split_field``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.stats import norm

from orientviz.adjust import gauss_newton
from orientviz.exercises._common import (
    INVERTERS,
    CheckFailed,
    call,
    compare,
    own_work,
    rng_for,
    success,
)


def _points(rng: np.random.Generator, n: int) -> np.ndarray:
    """Image points (mm) spread over a 230 mm format, not symmetric."""
    return rng.uniform(-110.0, 110.0, (n, 2))


def _radial(xy: np.ndarray, k: np.ndarray) -> np.ndarray:
    r2 = np.sum(xy**2, axis=1)
    return xy * (k[0] * r2 + (k[1] * r2**2 if len(k) > 1 else 0.0))[:, None]


def check_fit_k1(fn: Callable) -> None:
    """Check ``fn(xy, d) -> (k1, sigma0)`` for d = k1 r² (x, y) + noise (mm, mm⁻², mm)."""
    rng = rng_for("lesson11.check_fit_k1")
    xy = _points(rng, 14)
    k1 = 2.5e-9  # mm⁻²: 8.4 µm at r = 150 mm
    d = _radial(xy, np.array([k1])) + rng.normal(0.0, 0.0015, xy.shape)
    with own_work(gauss_newton=gauss_newton):
        out = call(fn, xy.copy(), d.copy(), what="fit_k1")
    try:
        k_hat, s0 = (float(v) for v in out)
    except (TypeError, ValueError):
        raise CheckFailed("return two numbers (k1, sigma0)") from None
    # oracle: the sum of squares is a parabola in k1; three values give its vertex
    a = (xy * np.sum(xy**2, axis=1)[:, None]).ravel()
    ks = np.array([0.0, 1e-9, 2e-9])
    cost = [np.sum((k * a - d.ravel()) ** 2) for k in ks]
    c2, c1, c0 = np.polyfit(ks, cost, 2)
    k_best = -c1 / (2 * c2)
    s_best = np.sqrt((c0 - c1**2 / (4 * c2)) / (d.size - 1))
    u = 1e-10  # compare in units of 1e-10 mm⁻²
    compare(
        "k1 [1e-10 mm⁻²]",
        k_hat / u,
        k_best / u,
        rtol=1e-6,
        wrong=[
            (
                "only the x equations were used",
                np.dot(a[0::2], d[:, 0]) / np.dot(a[0::2], a[0::2]) / u,
            ),
        ],
    )
    compare(
        "σ0 [µm]",
        s0 * 1000,
        s_best * 1000,
        rtol=1e-6,
        wrong=[
            (
                "divided by the number of coordinates 2n, not by the redundancy 2n − 1",
                1000 * s_best * np.sqrt((d.size - 1) / d.size),
            ),
            ("σ0² instead of σ0", 1000 * s_best**2),
        ],
    )
    success(f"k1 = {k_hat:.4g} mm⁻², σ0 = {s0 * 1000:.2f} µm (redundancy 2n − 1 = {d.size - 1})")


def _sigma_alone(Q: np.ndarray) -> float:
    """σ of parameter 0 (unit weight) if it were the only unknown: 1/√N₀₀ with N = Q⁻¹."""
    return 1.0 / np.sqrt(np.linalg.inv(Q)[0, 0])


@own_work(
    "the exercise is f from the entries of Q, worked out on paper — inverting Q (as the "
    "stand-in above does) skips the derivation",
    **INVERTERS,
)
def check_inflation(fn: Callable) -> None:
    """Check ``fn(Q) -> f``: by how much the σ of the first parameter grows because the second
    is estimated with it, from the 2 × 2 cofactor matrix Q of the joint adjustment:
    f = σ(joint) / σ(alone) = √Q₀₀ / (1/√N₀₀), N = Q⁻¹ (= 1/√(1 − ρ²)).

    Oracle: the normal matrix N recovered by inverting Q, and the one-parameter adjustment's
    σ = 1/√N₀₀ — no correlation formula. The answer may not invert Q or solve with it (numpy's
    and scipy's inverses and solvers are watched).
    """
    rng = rng_for("lesson11.check_inflation")
    for rho in (0.97, -0.6, 0.2):
        s = rng.uniform(0.5, 3.0, 2) * np.array([1.0, 1e-4])  # unequal sizes, as K1 and K2
        Q = np.array([[s[0] ** 2, rho * s[0] * s[1]], [rho * s[0] * s[1], s[1] ** 2]])
        want = np.sqrt(Q[0, 0]) / _sigma_alone(Q)
        got = call(fn, Q.copy(), what="inflation")
        try:
            got = float(got)
        except (TypeError, ValueError):
            raise CheckFailed(f"inflation: expected one number, got {got!r}") from None
        compare(f"σ(joint)/σ(alone) at ρ = {rho:+.2f}", got, want, rtol=1e-9, wrong=[
            ("1/(1 − ρ²) is the ratio of the VARIANCES; the σ grow by its square root", want**2),
            ("inverted: estimating the second parameter too cannot make the first more precise",
             1.0 / want),
            ("ρ itself is not the factor: f = 1/√(1 − ρ²)", abs(rho)),
            ("1/√(1 − |ρ|): ρ enters squared", 1.0 / np.sqrt(1.0 - abs(rho))),
            ("√(Q₀₀/Q₁₁) compares the two parameters, not one parameter with and without "
             "the other", np.sqrt(Q[0, 0] / Q[1, 1])),
        ])  # fmt: skip
    success("σ(joint)/σ(alone) right for ρ = +0.97, −0.6, +0.2")


def check_significant(fn: Callable) -> None:
    """Check ``fn(values, sigmas, alpha) -> bool array``: two-sided test abs(p)/σ_p > z(1 − α/2)."""
    values = np.array([2.1, -3.4, 0.52, 1.7, -0.9, 7.0, 1.5])  # µm
    sigmas = np.array([1.0, 1.2, 0.24, 0.95, 0.41, 6.0, 1.0])  # µm
    alpha = 0.05
    t = np.abs(values) / sigmas
    want = t > norm.ppf(1 - alpha / 2)
    got = np.asarray(call(fn, values.copy(), sigmas.copy(), alpha, what="significant"))
    if got.shape != want.shape:
        raise CheckFailed(
            f"expected one decision per parameter, shape {want.shape}, got {got.shape}"
        )
    got = got.astype(bool)
    if np.array_equal(got, want):
        success(
            f"t = {np.round(t, 2).tolist()}, k = {norm.ppf(1 - alpha / 2):.3f}: {got.astype(int).tolist()}"
        )
        return
    wrong = {
        "a one-sided critical value (1.645): the test is two-sided": t > norm.ppf(1 - alpha),
        "the sign was kept: test |value| / σ": values / sigmas > norm.ppf(1 - alpha / 2),
        "the value was not divided by its σ": np.abs(values) > norm.ppf(1 - alpha / 2),
        "t² was compared with k": t**2 > norm.ppf(1 - alpha / 2),
    }
    why = next(
        (w for w, v in wrong.items() if np.array_equal(got, v)),
        "compare t = |value|/σ with z(1 − α/2)",
    )
    raise CheckFailed(
        f"decisions {got.astype(int).tolist()}, expected {want.astype(int).tolist()}: {why}",
        error=np.inf,
        tolerance=0.0,
    )


def check_described_share(fn: Callable) -> None:
    """Check ``fn(A, d) -> (share_x, share_y)``: one joint fit d ≈ A p, shares of Σd² per axis."""
    rng = rng_for("lesson11.check_described_share")
    n, k = 40, 4
    A = rng.normal(size=(n, 2, k))
    d = np.einsum("nik,k->ni", A, rng.normal(size=k)) + rng.normal(0, 0.7, (n, 2)) * [1.0, 0.3]
    Qm, _ = np.linalg.qr(A.reshape(2 * n, k))  # oracle: orthogonal projection by QR
    rest = (d.ravel() - Qm @ (Qm.T @ d.ravel())).reshape(n, 2)
    want = 1 - np.sum(rest**2, axis=0) / np.sum(d**2, axis=0)
    got = call(fn, A.copy(), d.copy(), what="described_share")
    sep = []
    for i in range(2):  # x and y fitted separately
        Ai = A[:, i, :]
        r_i = d[:, i] - Ai @ np.linalg.lstsq(Ai, d[:, i], rcond=None)[0]
        sep.append(1 - np.sum(r_i**2) / np.sum(d[:, i] ** 2))
    both = 1 - np.sum(rest**2) / np.sum(d**2)
    compare(
        "(share x, share y)",
        got,
        want,
        rtol=1e-9,
        wrong=[
            ("the remainder's share (1 − described)", 1 - want),
            ("x and y fitted separately: the parameters are shared by both coordinates", sep),
            ("one share for x and y together", [both, both]),
        ],
    )
    success(f"described: x {want[0]:.1%}, y {want[1]:.1%}")


def check_fit_k1_real(fn: Callable) -> None:
    """Check ``fn(m, ideal, pp) -> K1`` of the backward model ideal = z (1 + K1 r²),
    z = m − pp, r² = ‖z‖² (measured points m and their ideal points, mm, on a 7 × 5 mm
    sensor; K1 in mm⁻²)."""
    rng = rng_for("lesson11.check_fit_k1_real")
    pp = np.array([3.61, -2.62])
    m = np.column_stack([rng.uniform(0.2, 7.1, 11), rng.uniform(-5.3, -0.1, 11)])
    k1 = 4.3e-3
    z = m - pp
    ideal = z * (1 + k1 * np.sum(z**2, axis=1))[:, None] + rng.normal(0, 3e-4, z.shape)
    got = call(fn, m.copy(), ideal.copy(), pp.copy(), what="fit_k1_real")
    try:
        got = float(got)
    except (TypeError, ValueError):
        raise CheckFailed("return one number, K1 in mm⁻²") from None
    # oracle: the sum of squares is a parabola in K1; three values give its vertex
    a = (z * np.sum(z**2, axis=1)[:, None]).ravel()
    ks = np.array([0.0, 2e-3, 4e-3])
    cost = [np.sum((z.ravel() + k * a - ideal.ravel()) ** 2) for k in ks]
    c2, c1, _ = np.polyfit(ks, cost, 2)
    want = -c1 / (2 * c2)
    zi = ideal  # the plausible wrong ideas, as numbers
    ri = np.sum(zi**2, axis=1)
    fwd = (zi * ri[:, None]).ravel()
    u = 1e-3
    compare(
        "K1 [1e-3 mm⁻²]",
        got / u,
        want / u,
        rtol=1e-6,
        wrong=[
            ("measured and ideal swapped (the forward model's direction)",
             fwd @ (z - zi).ravel() / (fwd @ fwd) / u),
            ("the radius of the ideal point, not of the measured one",
             ((z * ri[:, None]).ravel() @ (zi - z).ravel())
             / ((z * ri[:, None]).ravel() @ (z * ri[:, None]).ravel()) / u),
            ("not reduced to the principal point (r from the sensor corner)",
             (m * np.sum(m**2, axis=1)[:, None]).ravel() @ (ideal + pp - m).ravel()
             / np.sum((m * np.sum(m**2, axis=1)[:, None]) ** 2) / u),
        ],
    )  # fmt: skip
    success(f"K1 = {got:.5g} mm⁻² ({k1 * np.max(np.sum(z**2, axis=1)) ** 1.5 * 1000:.0f} µm "
            "at the farthest point)")  # fmt: skip
