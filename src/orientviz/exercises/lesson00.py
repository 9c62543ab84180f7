"""Checkers for lesson 00, the tour: σ̂0, redundancy, normalised residuals, the critical value.

Oracles (never :mod:`orientviz.adjust` or :mod:`orientviz.block`):

* σ̂0 and the redundancy from their definitions, evaluated on the checker's own numbers
  and on a block counted by hand;
* redundancy numbers from a QR factorisation of √P·A (the diagonal of the hat matrix),
  not from normal equations;
* the critical value from :func:`scipy.stats.norm.isf`.

Units: residuals and σ in mm (any unit, the same for both).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.stats import norm

from ._common import call, compare, rng_for, success

__all__ = [
    "check_critical_value",
    "check_normalized",
    "check_redundancy",
    "check_sigma0",
]

F64 = NDArray[np.float64]


def check_sigma0(sigma0: Callable[[F64, F64, int], float]) -> None:
    """``sigma0(v, sigma, r)`` must return σ̂0 = √(Σ (v/σ)² / r)."""
    rng = rng_for("lesson00.check_sigma0")
    n, r = 40, 25
    sigma = np.where(np.arange(n) % 3 == 0, 0.003, 0.008)
    v = rng.normal(0, 1, n) * sigma * 1.3
    truth = float(np.sqrt(np.sum((v / sigma) ** 2) / r))
    wrong = [
        ("the weights are missing: divide each residual by its σ", np.sqrt(np.sum(v**2) / r)),
        ("divided by n, not by the redundancy r", truth * np.sqrt(r / n)),
        ("the square root is missing (this is σ̂0²)", truth**2),
        ("weights 1/σ instead of 1/σ²", np.sqrt(np.sum(v**2 / sigma) / r)),
    ]
    got = float(call(sigma0, v.copy(), sigma.copy(), r, what="sigma0"))
    compare("σ̂0", got, truth, rtol=1e-9, wrong=wrong)
    success(f"σ̂0 = √(vᵀPv / r) = {got:.3f}")


def check_redundancy(redundancy: Callable[[int, int, int, int], int]) -> None:
    """``redundancy(n_images, n_tie, n_control, n_rays)`` of a bundle with fixed control points."""
    cases = [
        (2, 6, 4, 20),
        (18, 380, 8, 1021),
        (7, 45, 6, 190),
    ]  # the first by hand: 40 − 12 − 18 = 10
    for m, t, k, n in cases:
        truth = 2 * n - 6 * m - 3 * t
        wrong = [
            ("each ray gives two observations, x and y", n - 6 * m - 3 * t),
            ("fixed control points are not unknowns", 2 * n - 6 * m - 3 * (t + k)),
            ("an image has 6 orientation unknowns (X0, Y0, Z0, ω, φ, κ)", 2 * n - 7 * m - 3 * t),
        ]
        got = call(redundancy, m, t, k, n, what="redundancy")
        compare(
            f"redundancy of {m} images, {t} tie points, {n} rays",
            got,
            truth,
            rtol=1e-12,
            scale=1.0,
            wrong=wrong,
        )
    success("redundancy r = 2·rays − 6·images − 3·tie points")


def check_critical_value(critical_w: Callable[[float], float]) -> None:
    """``critical_w(alpha)`` must return k with P(abs(w) > k) = α for a standard normal w (two-sided)."""
    for alpha in (0.001, 0.05, 0.0027):
        truth = float(norm.isf(alpha / 2))
        wrong = [
            ("one-sided: |w| > k has α/2 in each tail", float(norm.isf(alpha))),
            ("α is a fraction (0.001 = 0.1 %), not a percentage", float(norm.isf(alpha / 200))),
        ]
        got = float(call(critical_w, alpha, what="critical_w"))
        compare(f"k for α = {alpha}", got, truth, rtol=1e-6, wrong=wrong)
    success("critical value: 3.29 for α = 0.1 %, 1.96 for 5 %")


def _line_problem(rng: np.random.Generator) -> tuple[F64, F64, F64]:
    """A weighted straight-line-plus-curvature fit: design A (n, 3), residuals v, σ."""
    t = np.sort(rng.uniform(-1, 1, 14))
    A = np.column_stack([np.ones_like(t), t, t**2])
    sigma = np.where(t > 0.3, 0.02, 0.005)
    l = A @ [1.0, -0.4, 0.2] + rng.normal(0, 1, t.size) * sigma
    l[5] += 0.05  # a blunder
    w = 1 / sigma
    x = np.linalg.lstsq(A * w[:, None], l * w, rcond=None)[0]
    return A, A @ x - l, sigma


def check_normalized(normalized: Callable[[F64, F64, F64], F64]) -> None:
    """``normalized(A, v, sigma)`` must return w_i = v_i / (σ_i √r_i) with the redundancy numbers r_i."""
    rng = rng_for("lesson00.check_normalized")
    A, v, sigma = _line_problem(rng)
    Q, _ = np.linalg.qr(A / sigma[:, None])
    r = 1.0 - np.sum(Q**2, axis=1)  # 1 − diagonal of the hat matrix of √P A
    truth = v / (sigma * np.sqrt(r))
    Qu, _ = np.linalg.qr(A)
    r_unweighted = 1.0 - np.sum(Qu**2, axis=1)
    wrong = [
        ("divide by σ·√r_i, not by σ alone (v/σ ignores the redundancy numbers)", v / sigma),
        ("the square root of r_i is missing", v / (sigma * r)),
        (
            "the redundancy numbers need the weights: r_i = 1 − (A N⁻¹ Aᵀ P)_ii",
            v / (sigma * np.sqrt(r_unweighted)),
        ),
    ]
    got = call(normalized, A.copy(), v.copy(), sigma.copy(), what="normalized")
    compare("normalised residuals w", got, truth, rtol=1e-8, wrong=wrong)
    success(
        f"normalised residuals; the largest |w| = {np.abs(got).max():.2f} sits on the blunder (observation {int(np.argmax(np.abs(got)))})"
    )
