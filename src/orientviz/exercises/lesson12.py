"""Checkers for lesson 12, gross errors: normalised residuals, data snooping, reliability.

Oracles: redundancy numbers from leave-one-out adjustments (the residual of an observation
is r_i times its residual when it is left out), scipy's normal quantiles and non-central χ²,
and the shift of the unknowns by an error of MDB size computed per observation — never the
library's ``gauss_newton``, ``data_snooping`` or ``reliability``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.stats import chi2, ncx2, norm

from orientviz.adjust.gross import redundancy_numbers, reliability
from orientviz.exercises._common import CheckFailed, call, compare, own_work, rng_for, success


def _wls(A: np.ndarray, l: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """Weighted least squares by scaling the rows (x̂)."""
    return np.linalg.lstsq(A / sigma[:, None], l / sigma, rcond=None)[0]


def _oracle_w(A, l, sigma):
    """v, r by leave-one-out, w = v/(σ √r)."""
    v = A @ _wls(A, l, sigma) - l
    r = np.empty(len(l))
    for i in range(len(l)):
        keep = np.arange(len(l)) != i
        e_out = l[i] - A[i] @ _wls(A[keep], l[keep], sigma[keep])  # residual when left out
        r[i] = -v[i] / e_out
    return v, r, v / (sigma * np.sqrt(r))


def _line(rng, n=12, blunder=None):
    """A straight line with unequal σ, points bunched at one end (unequal redundancy)."""
    t = np.sort(np.r_[rng.uniform(0, 3, n - 2), 9.0, 10.0])
    A = np.column_stack([np.ones(n), t, t**2 / 10])
    sigma = rng.uniform(0.5, 2.0, n)
    l = A @ [1.0, 0.5, -0.3] + rng.normal(0, sigma)
    if blunder is not None:
        i, size = blunder
        l[i] += size * sigma[i]
    return A, l, sigma


def check_normalized(fn: Callable) -> None:
    """Check ``fn(A, l, sigma) -> (v, r, w)``: residuals v = A x̂ − l, redundancy numbers, w."""
    rng = rng_for("lesson12.check_normalized")
    A, l, sigma = _line(rng)
    v, r, w = _oracle_w(A, l, sigma)
    with own_work(
        "the redundancy numbers are the core of your version: from your own Q_vv P",
        redundancy_numbers=redundancy_numbers,
    ):
        out = call(fn, A.copy(), l.copy(), sigma.copy(), what="normalized")
    try:
        v_got, r_got, w_got = (np.asarray(a, float) for a in out)
    except (TypeError, ValueError):
        raise CheckFailed("return three arrays (v, r, w)") from None
    vu = A @ np.linalg.lstsq(A, l, rcond=None)[0] - l
    compare("v", v_got, v, rtol=1e-8, wrong=[("the weights were forgotten (unweighted fit)", vu)])
    Hu = A @ np.linalg.solve(A.T @ A, A.T)
    compare(
        "r",
        r_got,
        r,
        rtol=1e-8,
        wrong=[
            ("that is 1 − r, the share of the observation in its own fit (h_ii)", 1 - r),
            ("the weights were forgotten in Q_vv P", 1 - np.diag(Hu)),
        ],
    )
    compare(
        "w",
        w_got,
        w,
        rtol=1e-8,
        wrong=[
            ("v/σ: the √r is missing", v / sigma),
            ("v/(σ r): r instead of √r", v / (sigma * r)),
            ("v/√r: σ is missing", v / np.sqrt(r)),
        ],
    )
    success(f"v, r and w right; Σr = {r.sum():.3f} = n − u = {len(l) - A.shape[1]}")


#: The lesson's design case: eight observations of a line bunched at T = 0 … 3.5 and one far
#: out at T = 12, all with σ = 1 (exercise 1 adds a tenth).
DESIGN_T = np.r_[np.arange(0.0, 4.0, 0.5), 12.0]


def _redundancy_by_leaving_out(T: np.ndarray) -> np.ndarray:
    """r_i of a straight line through equal-σ observations at T, by leave-one-out (the
    residual of l_i is r_i times its prediction error when left out), not from Q_vv P."""
    A = np.column_stack([np.ones_like(T), T])
    r = np.empty(len(T))
    for i in range(len(T)):
        l = np.zeros(len(T))
        l[i] = 1.0  # a unit error in l_i alone
        v_i = A[i] @ np.linalg.lstsq(A, l, rcond=None)[0] - 1.0
        keep = np.arange(len(T)) != i
        pred = A[i] @ np.linalg.lstsq(A[keep], l[keep], rcond=None)[0]  # = 0
        r[i] = -v_i / (1.0 - pred)
    return r


def check_new_position(fn: Callable) -> None:
    """Check ``fn() -> T``: where a tenth observation of the line (σ = 1) must go so that no
    observation's minimal detectable bias exceeds 6 σ (α0 = 0.1 %, β0 = 80 %).

    Oracle: the redundancy numbers of all ten observations by leave-one-out, δ0 from scipy's
    normal quantiles.
    """
    got = call(fn, what="new_position")
    try:
        t_new = float(got)
    except (TypeError, ValueError):
        raise CheckFailed(f"new_position: expected one number T, got {got!r}") from None
    if not 0.0 <= t_new <= 30.0:
        raise CheckFailed(f"new_position: T = {t_new:g} lies outside the line's 0 … 30")
    d0 = norm.isf(0.001 / 2) + norm.ppf(0.80)
    mdb = d0 / np.sqrt(_redundancy_by_leaving_out(np.r_[DESIGN_T, t_new]))  # in σ
    worst = int(np.argmax(mdb))
    if mdb[worst] <= 6.0:
        success(
            f"T = {t_new:g}: largest MDB {mdb[worst]:.2f} σ (the far point {mdb[8]:.2f} σ, "
            f"the new one {mdb[9]:.2f} σ)"
        )
        return
    if worst == 9:
        why = (
            "now the NEW observation is the lonely one: nothing checks it, so its own MDB is "
            "the largest — it must stay close enough to the far point that each checks the other"
        )
    elif t_new <= 4.0:
        why = (
            "among the others it checks only what is checked already; the far point stays alone "
            "and unchecked"
        )
    else:
        why = "closer to the far point: it must share the far point's leverage to check it"
    raise CheckFailed(
        f"new_position: T = {t_new:g} leaves observation {worst} (T = "
        f"{np.r_[DESIGN_T, t_new][worst]:g}) with an MDB of {mdb[worst]:.2f} σ > 6 σ — {why}",
        error=np.inf,
        tolerance=0.0,
    )


def check_flag_probability(fn: Callable) -> None:
    """Check ``fn(nabla, sigma, sigma_true, r, k) -> P``: the probability that the w-test
    abs(w) > k flags an observation with the error ``nabla`` whose σ is ``sigma_true`` while the
    test divides by the stated ``sigma`` (redundancy number ``r``), arrays.

    Oracle: (w σ/σ_true)² is non-central χ² with one degree of freedom and non-centrality
    r ∇²/σ_true² (scipy's ncx2), and P = P(that > k² σ²/σ_true²) — not the normal tails.
    """
    k = norm.isf(0.001 / 2)
    nabla = np.array([0.0, 0.0, 0.004, 0.010, 0.018, 0.030, -0.012])
    sigma = np.array([0.005, 0.005, 0.005, 0.003, 0.008, 0.004, 0.005])
    true = sigma * np.array([1.0, 1.5, 1.0, 1.3, 0.8, 1.0, 2.0])
    r = np.array([0.6, 0.4, 0.3, 0.85, 0.5, 0.12, 0.7])
    s = true / sigma  # the standard deviation of w
    want = _chi2_sf(k**2 / s**2, r * nabla**2 / true**2)
    got = call(fn, nabla.copy(), sigma.copy(), true.copy(), r.copy(), k, what="flag_probability")
    m = np.sqrt(r) * np.abs(nabla) / sigma  # |E(w)|

    def tails(mean: np.ndarray, sd: np.ndarray | float = 1.0) -> np.ndarray:
        return norm.sf((k - mean) / sd) + norm.cdf((-k - mean) / sd)

    compare("P(|w| > k)", got, want, rtol=1e-6, scale=1.0, wrong=[
        ("σ_true is left out: w = v/(σ√r) is divided by the STATED σ, so its standard deviation "
         "is σ_true/σ, not 1", tails(m)),
        ("E(w) = √r ∇/σ_true with standard deviation 1: w is divided by the stated σ, so its mean "
         "is √r ∇/σ and its standard deviation σ_true/σ", tails(m * sigma / true)),
        ("one tail only: a clean observation (∇ = 0) is flagged on both sides", norm.sf((k - m) / s)),
        ("√r is missing: E(w) = √r ∇/σ", tails(np.abs(nabla) / sigma, s)),
        ("the probability of NOT flagging it (1 − P)", 1 - want),
        ("the variance (σ_true/σ)² used as the standard deviation", tails(m, s**2)),
    ])  # fmt: skip
    success(
        f"P(|w| > k) right: a clean observation whose σ is 1.5 times the stated one is flagged "
        f"with probability {want[1]:.1%} (α0 = 0.1 % when σ is right)"
    )


def _chi2_sf(x: float, lam: np.ndarray) -> np.ndarray:
    """P(χ'²₁(λ) > x) for each λ (scipy's non-central χ²; the central one at λ = 0)."""
    return np.where(lam > 0, ncx2.sf(x, 1, np.maximum(lam, 1e-300)), chi2.sf(x, 1))


def check_bias_to_noise(fn: Callable) -> None:
    """Check ``fn(r, delta0) -> ratio``: the largest effect of an undetected error of MDB size in
    observation i on any function f = cᵀx̂ of the unknowns, in units of σ_f (arrays r).

    Oracle: on a random weighted line fit, Δx̂ = N⁻¹AᵀPe_i∇₀ computed for every observation and
    √(Δx̂ᵀNΔx̂) — the largest abs(cᵀΔx̂)/σ_f over all c (Cauchy–Schwarz) — with r from the leave-one-
    out adjustments; not a formula in r.
    """
    rng = rng_for("lesson12.check_bias_to_noise")
    A, l, sigma = _line(rng)
    _, r, _ = _oracle_w(A, l, sigma)
    d0 = norm.isf(0.001 / 2) + norm.ppf(0.80)
    N = A.T @ (A / sigma[:, None] ** 2)
    want = np.empty(len(l))
    for i in range(len(l)):
        e = np.zeros(len(l))
        e[i] = d0 * sigma[i] / np.sqrt(r[i])  # an error of MDB size
        dx = np.linalg.solve(N, A.T @ (e / sigma**2))
        want[i] = np.sqrt(dx @ N @ dx)
    with own_work(reliability=reliability):
        got = call(fn, r.copy(), d0, what="bias_to_noise")
    compare("largest |Δf|/σ_f per observation", got, want, rtol=1e-6, wrong=[
        ("δ0/√r is the MDB in units of the observation's σ, not its effect on the unknowns",
         d0 / np.sqrt(r)),
        ("δ0 √(1 − r): the MDB is δ0 σ/√r, not δ0 σ", d0 * np.sqrt(1 - r)),
        ("(1 − r)/r needs its square root: the ratio is √(ΔxᵀNΔx)", d0 * (1 - r) / r),
        ("inverted: a small r (little control) must give a LARGE effect",
         d0 * np.sqrt(r / (1 - r))),
    ])  # fmt: skip
    success(
        f"δ̄0 = δ0 √((1 − r)/r): from {want.min():.2f} to {want.max():.2f} on this line "
        f"(r from {r.max():.2f} to {r.min():.2f})"
    )


def check_snoop(fn: Callable) -> None:
    """Check ``fn(adjust, n, k) -> list``: data snooping to the end. ``adjust(keep)`` adjusts with
    the observations where the boolean mask ``keep`` (n,) is True and returns their normalised
    residuals (n,) (NaN where not kept); the answer lists the rejected indices in order."""
    rng = rng_for("lesson12.check_snoop")
    k = norm.ppf(1 - 0.001 / 2)
    n = 24
    t = np.linspace(0.0, 10.0, n)
    A = np.column_stack([np.ones(n), t, t**2 / 10])
    sigma = np.full(n, 1.0)
    l = A @ [1.0, 0.5, -0.3] + np.clip(rng.normal(0, 1.0, n), -2, 2)
    planted = {0: 14.0, 2: 11.0, 17: -7.5}  # 0 and 2 smear into their neighbours' w
    for i, size in planted.items():
        l[i] += size
    calls = []

    def adjust(keep):
        keep = np.asarray(keep, dtype=bool)
        if keep.shape != (n,):
            raise CheckFailed(
                f"snoop: adjust(keep) needs a boolean mask of shape ({n},), got {keep.shape}."
            )
        calls.append(keep.copy())
        w = np.full(n, np.nan)
        w[keep] = _oracle_w(A[keep], l[keep], sigma[keep])[2]
        return w

    got = call(fn, adjust, n, k, what="snoop")
    try:
        got = [int(i) for i in got]
    except (TypeError, ValueError):
        raise CheckFailed(f"snoop: expected a list of indices, got {got!r}.") from None
    want = set(planted)
    if set(got) == want and len(got) == len(want):
        if len(calls) != len(want) + 1:
            raise CheckFailed(
                f"snoop: the right observations, but adjust was called {len(calls)} times: "
                f"one rejection per adjustment and a last one that finds nothing ({len(want) + 1})",
                error=1.0, tolerance=0.0,
            )  # fmt: skip
        success(
            f"data snooping: the {len(want)} planted blunders and nothing else, one per adjustment"
        )
        return
    first = adjust(np.ones(n, bool))
    calls.pop()
    why = ""
    if set(got) == set(np.flatnonzero(np.abs(first) > k).tolist()) and len(calls) <= 1:
        why = "these are all |w| > k of the first adjustment: reject one at a time and adjust again (a blunder's w spreads to its neighbours)"  # noqa: E501
    elif want - set(got) and all(first[i] < 0 for i in want - set(got)):
        why = "the blunders with a negative w were kept: compare |w| with k, not w"
    elif len(got) > len(want):
        why = "innocent observations were rejected too — stop when the largest |w| of the current adjustment is ≤ k"
    elif len(got) < len(want):
        why = "a blunder was kept — go on until no |w| exceeds k"
    raise CheckFailed(
        f"snoop: rejected {got}, the planted blunders are {sorted(want)}" + (f" — {why}." if why else "."),
        error=1.0, tolerance=0.0,
    )  # fmt: skip
