"""Checkers for lesson 00, the tour: σ̂0, redundancy, the critical value of n tests, a prediction.

Oracles (never :mod:`orientviz.adjust` or :mod:`orientviz.block`):

* σ̂0 and the redundancy from their definitions, evaluated on the checker's own numbers
  and on a block counted by hand;
* the prediction for doubled σ checked by the experiment: the fit adjusted again with σ
  doubled (σ̂0, redundancy numbers from a QR factorisation of √P·A, normalised residuals);
* the critical value of n tests: the probability of at least one false alarm evaluated from
  :func:`scipy.stats.norm.sf` and solved for k by bracketing.

Units: residuals and σ in mm (any unit, the same for both).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import brentq
from scipy.stats import norm

from ._common import CheckFailed, call, compare, rng_for, success

__all__ = [
    "check_family_critical",
    "check_after_doubling",
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


def check_redundancy(redundancy: Callable[..., int]) -> None:
    """``redundancy(n_images, n_tie, n_control, n_rays, weighted_control)`` of a bundle whose
    full control points are fixed (``weighted_control=False``) or enter as unknowns with their
    given coordinates as weighted observations (``True``)."""
    cases = [
        (2, 6, 4, 20),
        (18, 380, 8, 1021),
        (7, 45, 6, 190),
    ]  # the first by hand: 40 − 12 − 18 = 10
    for weighted in (False, True):
        for m, t, k, n in cases:
            truth = 2 * n - 6 * m - 3 * t  # weighted: + 3k observations, + 3k unknowns
            wrong = [
                ("each ray gives two observations, x and y", n - 6 * m - 3 * t),
                ("an image has 6 orientation unknowns (X0, Y0, Z0, ω, φ, κ)",
                 2 * n - 7 * m - 3 * t),
            ]  # fmt: skip
            if weighted:
                wrong += [
                    ("weighted control points are unknowns (3 each) AND observations (their 3 "
                     "given coordinates): the unknowns alone are counted here",
                     2 * n - 6 * m - 3 * (t + k)),
                    ("weighted control points add 3 observations each but also 3 unknowns",
                     2 * n + 3 * k - 6 * m - 3 * t),
                ]  # fmt: skip
            else:
                wrong.append(("fixed control points are not unknowns", 2 * n - 6 * m - 3 * (t + k)))
            got = call(redundancy, m, t, k, n, weighted, what="redundancy")
            compare(
                f"redundancy of {m} images, {t} tie points, {k} control points "
                f"({'weighted' if weighted else 'fixed'}), {n} rays",
                got,
                truth,
                rtol=1e-12,
                scale=1.0,
                wrong=wrong,
            )
    success("redundancy r = 2·rays − 6·images − 3·tie points, fixed or weighted control alike")


def check_family_critical(critical_w: Callable[[float, int], float]) -> None:
    """``critical_w(alpha_family, n)`` must return k such that n independent clean standard
    normal w_i give P(at least one abs(w_i) > k) = alpha_family (two-sided per observation).

    Oracle: that probability, 1 − (1 − 2Φ(−k))ⁿ, evaluated from scipy's normal tail and solved
    for k by bracketing (brentq) — not the closed form the student writes.
    """
    for alpha_f, n in ((0.05, 2042), (0.3, 5), (0.5, 2), (0.01, 40)):

        def family(k: float, n: int = n, alpha_f: float = alpha_f) -> float:
            return float(-np.expm1(n * np.log1p(-2.0 * norm.sf(k)))) - alpha_f

        truth = float(brentq(family, 0.01, 40.0, xtol=1e-14))
        wrong = [
            ("one-sided: |w_i| > k has half of each observation's α in each tail",
             float(norm.isf(1.0 - (1.0 - alpha_f) ** (1.0 / n)))),
            ("n is left out: this is the k of ONE observation at α = α_F",
             float(norm.isf(alpha_f / 2.0))),
            ("α_F/n per observation is Bonferroni's bound; for n independent tests "
             "1 − (1 − α)ⁿ = α_F gives α exactly", float(norm.isf(alpha_f / (2.0 * n)))),
            ("α_F·n per observation: the more observations, the SMALLER each one's α must be",
             float(norm.isf(min(alpha_f * n, 0.999) / 2.0))),
            ("α is a fraction (0.05 = 5 %), not a percentage",
             float(norm.isf((1.0 - (1.0 - alpha_f) ** (1.0 / n)) / 200.0))),
        ]  # fmt: skip
        got = float(call(critical_w, alpha_f, n, what="critical_w"))
        compare(f"k for α_F = {alpha_f}, n = {n}", got, truth, rtol=1e-6, wrong=wrong)
    success("critical value of n tests: 4.21 for one false alarm in 20 blocks of 2042 observations")


def _adjusted(A: F64, l: F64, sigma: F64) -> tuple[float, F64, F64]:
    """σ̂0, redundancy numbers and normalised residuals of a weighted fit, by QR (the oracle)."""
    Q, R = np.linalg.qr(A / sigma[:, None])
    x = np.linalg.solve(R, Q.T @ (l / sigma))
    v = A @ x - l
    r_i = 1.0 - np.sum(Q**2, axis=1)  # 1 − diagonal of the hat matrix of √P A
    s0 = float(np.sqrt(np.sum((v / sigma) ** 2) / (len(l) - A.shape[1])))
    return s0, r_i, v / (sigma * np.sqrt(r_i))


def check_after_doubling(after_doubling: Callable[[float, F64, F64], tuple]) -> None:
    """``after_doubling(sigma0, r_i, w)`` must predict (σ̂0, r_i, w) after every a-priori σ is
    doubled (the measurements unchanged), from the values before."""
    rng = rng_for("lesson00.check_after_doubling")
    t = np.sort(rng.uniform(-1, 1, 14))
    A = np.column_stack([np.ones_like(t), t, t**2])
    sigma = np.where(t > 0.3, 0.02, 0.005)
    l = A @ [1.0, -0.4, 0.2] + rng.normal(0, 1, t.size) * sigma
    l[5] += 0.05  # a blunder
    before = _adjusted(A, l, sigma)
    after = _adjusted(A, l, 2.0 * sigma)  # the experiment: adjust again with σ doubled
    got = call(after_doubling, before[0], before[1].copy(), before[2].copy(), what="after_doubling")
    if not isinstance(got, tuple) or len(got) != 3:
        raise CheckFailed("after_doubling: return the three predictions (sigma0, r_i, w)")
    compare("σ̂0 after doubling σ", got[0], after[0], rtol=1e-9, wrong=[
        ("σ̂0 = √(Σ(v/σ)²/r): the same residuals divided by a doubled σ halve it", 2 * before[0]),
        ("σ̂0 changes: the residuals stay, σ doubles", before[0]),
    ])  # fmt: skip
    compare("redundancy numbers r_i after doubling σ", got[1], after[1], rtol=1e-9, wrong=[
        ("r_i depend on the relative weights only; doubling every σ leaves them", before[1] / 2),
        ("r_i depend on the relative weights only; doubling every σ leaves them", before[1] / 4),
    ])  # fmt: skip
    compare("normalised residuals w after doubling σ", got[2], after[2], rtol=1e-9, wrong=[
        ("w = v/(σ√r_i): v and r_i stay, σ doubles, so w halves", before[2]),
        ("w = v/(σ√r_i): v and r_i stay, σ doubles, so w halves", 2 * before[2]),
    ])  # fmt: skip
    success(
        f"σ̂0 {before[0]:.2f} → {after[0]:.2f}, r_i unchanged, the blunder's |w| "
        f"{np.abs(before[2]).max():.1f} → {np.abs(after[2]).max():.1f}: an honest σ matters"
    )
