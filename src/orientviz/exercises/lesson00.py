"""Checkers for lesson 00, the tour: σ̂0, redundancy, false alarms of the w-test, a prediction.

Oracles (never :mod:`orientviz.adjust` or :mod:`orientviz.block`):

* σ̂0 and the redundancy from their definitions, evaluated on the checker's own numbers
  and on a block counted by hand;
* the prediction for doubled σ checked by the experiment: the fit adjusted again with σ
  doubled (σ̂0, redundancy numbers from a QR factorisation of √P·A, normalised residuals);
* the expected number of false alarms: n times the normal density integrated beyond ±k.

Units: residuals and σ in mm (any unit, the same for both).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import quad
from scipy.stats import norm

from ._common import CheckFailed, call, compare, rng_for, success

__all__ = [
    "check_flagged_clean",
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


def check_flagged_clean(flagged_clean: Callable[[int, float], float]) -> None:
    """``flagged_clean(n, k)`` must return the expected number of n clean observations, each with
    a standard normal normalised residual, that the w-test abs(w) > k flags.

    Oracle: n times the normal density integrated beyond ±k (scipy's quad), not the tail
    function the student uses.
    """
    for n, k in ((2042, 3.29), (40, 2.5), (500, 1.96), (7, 0.8)):
        tail = quad(norm.pdf, k, np.inf)[0] + quad(norm.pdf, -np.inf, -k)[0]
        truth = n * tail
        wrong = [
            ("one tail only: |w| > k counts both w > k and w < −k", n * tail / 2),
            ("that is the probability for ONE observation; the question is the number among n",
             tail),
            ("the probability that a clean observation PASSES, times n", n * (1 - tail)),
            ("1 − (1 − α)ⁿ is the chance of at least one false alarm, not their expected number",
             1 - (1 - tail) ** n),
        ]  # fmt: skip
        got = float(call(flagged_clean, n, k, what="flagged_clean"))
        compare(f"false alarms among n = {n} at k = {k}", got, truth, rtol=1e-8, wrong=wrong)
    success("false alarms: n · P(|w| > k) — about 2 among the tour's 2042 observations at k = 3.29")


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
