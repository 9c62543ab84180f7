"""Checkers for lesson 11, systematic image errors and self-calibration.

Oracles: error-free simulated distortion with known coefficients (for the real camera's
exercise a three-term radial lens fitted by one term, brute force), the one-parameter
adjustment from the normal matrix recovered by inverting Q, scipy's binomial distribution for
the level of several tests together, and a projection for the share of a field that a
parameter set and the orientation describe (an SVD) — never the library's ``self_calibrate``,
``analyse`` or ``split_field``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.integrate import quad
from scipy.stats import binom

from orientviz.adjust import gauss_newton
from orientviz.bundle import Ebner12
from orientviz.exercises._common import (
    INVERTERS,
    CheckFailed,
    call,
    compare,
    own_work,
    rng_for,
    success,
)
from orientviz.simulate import systematic as se


def _points(rng: np.random.Generator, n: int) -> np.ndarray:
    """Image points (mm) spread over a 230 mm format, not symmetric."""
    return rng.uniform(-110.0, 110.0, (n, 2))


def _radial(xy: np.ndarray, k: np.ndarray) -> np.ndarray:
    r2 = np.sum(xy**2, axis=1)
    return xy * (k[0] * r2 + (k[1] * r2**2 if len(k) > 1 else 0.0))[:, None]


def check_k1_alone_format(fn: Callable) -> None:
    """Check ``fn(K, rho) -> K1``: the K1 a one-term fit returns when the points fill a round
    format of radius ``rho`` (mm) evenly and the lens is exactly Δ = (K1 r² + K2 r⁴ + K3 r⁶) z.

    Oracle: the sums of the one-term normal equation as integrals over the disc,
    ∫₀^ρ f(r) 2πr dr, by adaptive quadrature (scipy's quad) — not the closed form. A fit to
    sampled points or a coarse numerical integral comes close but not to 1e-10, and is named.
    """
    for K, rho in (((4.6e-3, -4.5e-5, -2.1e-6), 3.6), ((-2.3e-3, 3.1e-4, 1.2e-5), 2.2)):
        K = np.array(K)

        def moment(n: int, rho: float = rho) -> float:
            return quad(lambda r: r**n * 2.0 * np.pi * r, 0.0, rho, epsabs=0.0, epsrel=1e-13)[0]

        want = (K[0] * moment(6) + K[1] * moment(8) + K[2] * moment(10)) / moment(6)
        got = call(fn, K.copy(), rho, what="k1_alone_format")
        try:
            got = float(got)
        except (TypeError, ValueError):
            raise CheckFailed(f"k1_alone_format: expected one number, got {got!r}") from None
        u = 1e-3
        err = abs(got - want) / abs(want)
        wrong = [
            ("the area element is missing: points spread evenly over the AREA, so the sums "
             "become ∫ f(r) 2πr dr, not ∫ f(r) dr",
             (K[0] + K[1] * 7 / 9 * rho**2 + K[2] * 7 / 11 * rho**4) / u),
            ("every point at the rim (r = ρ): the points fill the format from its centre",
             (K[0] + K[1] * rho**2 + K[2] * rho**4) / u),
            ("the lens's own K1: alone, K1 also takes over what K2 and K3 describe", K[0] / u),
        ]  # fmt: skip
        if 1e-10 < err < 1e-3 and not any(abs(got / u - w) < 1e-9 * abs(w) for _, w in wrong):
            raise CheckFailed(
                f"k1_alone_format for K = {K.tolist()}, ρ = {rho} mm: right to {err:.0e} but not "
                "exactly — a fit to sampled points or a numerical integral? Points spread evenly "
                "turn the sums of your normal equation into integrals ∫₀^ρ … 2πr dr, and those "
                "have closed forms.",
                error=err,
                tolerance=1e-10,
            )
        compare(f"K1 of one term on a format of radius {rho} mm [1e-3 mm⁻²] for K = {K.tolist()}",
                got / u, want / u, rtol=1e-10, wrong=wrong)  # fmt: skip
    success(
        "K1 of a one-term fit on a round format filled evenly: right for both lenses and formats"
    )


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


def inflation_library(Q: np.ndarray) -> float:
    """σ(joint)/σ(alone) of parameter 0 by inverting Q (the lesson's stand-in while
    ``inflation`` is a blank; its check refuses it: the exercise is the derivation).

    Parameters
    ----------
    Q : numpy.ndarray, shape (2, 2)
        Cofactor matrix of two parameters estimated together.

    Returns
    -------
    float
        The factor by which the σ of parameter 0 grows because parameter 1 is estimated too.
    """
    return float(np.sqrt(Q[0, 0] * np.linalg.inv(Q)[0, 0]))


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


def check_per_test_alpha(fn: Callable) -> None:
    """Check ``fn(family, m) -> alpha``: the level of each of m independent tests such that
    at least one of them rejects with probability ``family`` when every tested value is 0
    (α = 1 − (1 − family)^(1/m)).

    Oracle: the binomial distribution of the number of rejections (scipy), evaluated at the
    student's α — not the closed form.
    """
    cases = ((0.05, 12), (0.01, 44), (0.10, 3))
    for family, m in cases:
        got = call(fn, family, m, what="per_test_alpha")
        try:
            got = float(got)
        except (TypeError, ValueError):
            raise CheckFailed(f"per_test_alpha: expected one number, got {got!r}") from None
        if not 0.0 < got < 1.0:
            raise CheckFailed(
                f"per_test_alpha({family}, {m}) = {got:.4g}: a level is a probability in (0, 1)"
            )
        level = float(binom.sf(0, m, got))  # P(at least one of m tests rejects)
        want = 1.0 - (1.0 - family) ** (1.0 / m)
        if abs(level - family) <= 1e-9 * family:
            continue
        pct = f"{level:.4%}"
        wrong = [
            (
                f"α/m is Bonferroni's bound: the {m} tests together then reject with "
                f"probability {pct}, below {family:.0%} — safe but not the level asked for; "
                f"no test rejects with probability (1 − α)^m",
                family / m,
            ),
            (
                f"each test at the family's level: {m} tests together reject with probability "
                f"{pct}",
                family,
            ),
            (f"multiplied by m instead of divided: together {pct}", family * m),
            (
                "this is the probability that ONE test does not reject; the level is 1 minus it",
                (1.0 - family) ** (1.0 / m),
            ),
            (
                f"1 − (1 − α)^m is the level of {m} tests at α = {family}, the question "
                "turned round",
                1.0 - (1.0 - family) ** m,
            ),
        ]
        compare(f"α per test for {m} tests at {family:.0%} together", got, want, rtol=1e-9,
                wrong=wrong)  # fmt: skip
    success(
        "the tests together keep their level: e.g. 12 tests at "
        f"{1.0 - 0.95 ** (1 / 12):.4%} each reject together with probability 5 %"
    )


def _eo_columns(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The six image deformations an exterior orientation makes (shifts, scale, rotation,
    two projective tilts), (n, 2, 6)."""
    o, one = np.zeros_like(x), np.ones_like(x)
    cols = [(one, o), (o, one), (x, y), (-y, x), (x * x, x * y), (x * y, y * y)]
    return np.stack([np.column_stack(c) for c in cols], axis=2)


def _shares(A: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Share of Σd² per axis that the columns of A (n, 2, k) describe (projection onto their
    span by an SVD, so a column that repeats others changes nothing)."""
    n = d.shape[0]
    M = A.reshape(2 * n, -1)
    M = M / np.maximum(np.linalg.norm(M, axis=0), 1e-300)  # columns of any unit alike
    U, s, _ = np.linalg.svd(M, full_matrices=False)
    U = U[:, s > 1e-10 * s[0]]
    rest = (d.ravel() - U @ (U.T @ d.ravel())).reshape(n, 2)
    return 1.0 - np.sum(rest**2, axis=0) / np.sum(d**2, axis=0)


def check_trough_term(fn: Callable) -> None:
    """Check ``fn(xy) -> (n, 2)``: the image field (per unit) of one additional parameter
    that, added to Ebner's 12 terms and the orientation's six deformations, describes a film
    trough in x and in y (≥ 99.9 % of its squares each).

    Oracle: a trough of another size and principal distance on a grid the lesson does not use,
    projected onto the span of the columns (Ebner's design and the six deformations built here).
    """
    g = np.linspace(-110.0, 110.0, 9)
    xy = np.array([(a, b) for a in g for b in g])
    trough = se.unflatness(6.0, c=153.0)
    d = np.asarray(trough(xy, np.zeros(len(xy), int)), float)
    with own_work(
        "the trough's own field describes the trough trivially (a physical model of the film, "
        "the other way the lesson names); the exercise is the one polynomial term that is "
        "missing",
        unflatness=trough.field,  # the code every se.unflatness(...) field runs
    ):
        col = call(fn, xy.copy(), what="trough_term")
    col = np.asarray(col, dtype=float)
    if col.shape != xy.shape:
        raise CheckFailed(
            f"trough_term: expected the field at each point, shape {xy.shape}, got {col.shape}"
        )
    if not np.all(np.isfinite(col)) or not np.any(col):
        raise CheckFailed("trough_term: the field is zero or not finite")
    k = float(col.ravel() @ d.ravel() / (d.ravel() @ d.ravel()))
    if np.max(np.abs(col - k * d)) <= 1e-6 * np.max(np.abs(col)):
        raise CheckFailed(
            "trough_term: that is the trough itself (a physical model of the film) — the "
            "exercise asks which one polynomial term Ebner's 12 lack"
        )
    base = np.concatenate([Ebner12().design(xy), _eo_columns(xy[:, 0], xy[:, 1])], axis=2)
    before = _shares(base, d)
    after = _shares(np.concatenate([base, col[:, :, None]], axis=2), d)
    if np.all(after >= 0.999):
        success(
            f"with your term the set describes x {after[0]:.2%} (was {before[0]:.1%}), "
            f"y {after[1]:.2%} (was {before[1]:.1%})"
        )
        return
    text = f"x {after[0]:.1%} (was {before[0]:.1%}), y {after[1]:.1%} (was {before[1]:.1%})"
    if np.max(np.abs(col[:, 0])) < 1e-12 * np.max(np.abs(col)):
        why = (
            "a term in y only: the y part was described already; the missing part is in x "
            "(x·h(x)/c with h quadratic in x)"
        )
    elif np.all(np.abs(after - before) < 1e-6):
        why = (
            "your term adds nothing: it is a combination of Ebner's terms and the orientation's "
            "deformations already"
        )
    else:
        radial = xy * np.sum(xy**2, axis=1)[:, None]
        kr = float(col.ravel() @ radial.ravel() / (radial.ravel() @ radial.ravel()))
        if np.max(np.abs(col - kr * radial)) <= 1e-6 * np.max(np.abs(col)):
            why = (
                "a radial r² term (K1): the trough moves points along the radius by h/c, but h "
                "depends on x alone, not on r"
            )
        else:
            why = (
                "the part left is in x: x·h(x)/c with h quadratic in x — which power of x in "
                "the x coordinate has neither a term nor the orientation?"
            )
    raise CheckFailed(f"trough_term: described {text}: {why}", error=np.inf, tolerance=0.0)


def check_k1_alone(fn: Callable) -> None:
    """Check ``fn(K, r) -> K1``: the K1 a one-term fit Δ = K1 r² z returns when the lens is
    exactly Δ = (K1 r² + K2 r⁴ + K3 r⁶) z, from points at the radii r (mm; K in mm⁻², mm⁻⁴,
    mm⁻⁶).

    Oracle: error-free points of the three-term lens at those radii in random directions, the
    one-term least-squares sum of squares sampled at three values of K1 (a parabola's vertex)
    — not the closed form.
    """
    rng = rng_for("lesson11.check_k1_alone")
    for K, n in (((4.6e-3, -4.5e-5, -2.1e-6), 12), ((-2.3e-3, 3.1e-4, 0.0), 20)):
        K = np.array(K)
        r = rng.uniform(0.3, 3.6, n)
        ang = rng.uniform(0.0, 2 * np.pi, n)
        z = r[:, None] * np.column_stack([np.cos(ang), np.sin(ang)])
        lens = z * (K[0] * r**2 + K[1] * r**4 + K[2] * r**6)[:, None]
        a = (z * (r**2)[:, None]).ravel()
        ks = np.array([-1e-2, 0.0, 1e-2])
        cost = [np.sum((k * a - lens.ravel()) ** 2) for k in ks]
        c2, c1, _ = np.polyfit(ks, cost, 2)
        want = -c1 / (2 * c2)
        got = call(fn, K.copy(), r.copy(), what="k1_alone")
        try:
            got = float(got)
        except (TypeError, ValueError):
            raise CheckFailed(f"k1_alone: expected one number, got {got!r}") from None
        s6 = np.sum(r**6)
        u = 1e-3
        compare(f"K1 of one term [1e-3 mm⁻²] for K = {K.tolist()}", got / u, want / u, rtol=1e-6,
                wrong=[
                    ("the lens's own K1: alone, K1 also takes over what K2 and K3 describe — "
                     "write the one-term normal equation with the three-term field as the data",
                     K[0] / u),
                    ("K3 forgotten", (K[0] + K[1] * np.sum(r**8) / s6) / u),
                    ("plain means of r² and r⁴: the points weigh with r⁶ (the square of the "
                     "K1 column r² z)",
                     (K[0] + K[1] * np.mean(r**2) + K[2] * np.mean(r**4)) / u),
                    ("weights r⁴: the column of K1 is r²·z, whose square is r⁶, not r⁴",
                     (K[0] + K[1] * np.sum(r**6) / np.sum(r**4)
                      + K[2] * np.sum(r**8) / np.sum(r**4)) / u),
                ])  # fmt: skip
    success("K1 of a one-term fit = K1 + K2·Σr⁸/Σr⁶ + K3·Σr¹⁰/Σr⁶, for both lenses")
