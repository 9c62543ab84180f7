"""Checkers for lesson 12, gross errors: normalised residuals, data snooping, reliability.

Oracles: redundancy numbers from leave-one-out adjustments (the residual of an observation
is r_i times its residual when it is left out), scipy's normal quantiles, and the shift of
the unknowns by brute force (adjust with and without the error) — never the library's
``gauss_newton``, ``data_snooping`` or ``reliability``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.stats import norm

from orientviz.exercises._common import CheckFailed, call, compare, rng_for, success


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


def check_snoop_round(fn: Callable) -> None:
    """Check ``fn(A, l, sigma, k) -> index``: the observation with the largest abs(w) if > k, else −1."""
    rng = rng_for("lesson12.check_snoop_round")
    k = norm.ppf(1 - 0.001 / 2)
    cases = [_line(rng, blunder=(11, -6.0)), _line(rng), _line(rng, blunder=(2, 9.0))]
    for n_case, (A, l, sigma) in enumerate(cases, start=1):
        _, r, w = _oracle_w(A, l, sigma)
        i = int(np.argmax(np.abs(w)))
        want = i if abs(w[i]) > k else -1
        got = call(fn, A.copy(), l.copy(), sigma.copy(), k, what="snoop_round")
        got = int(got)
        if got == want:
            continue
        v = A @ _wls(A, l, sigma) - l
        why = {
            int(np.argmax(w)): "the largest w with its sign: test |w|",
            int(np.argmax(np.abs(v))): "the largest |v|, not the largest normalised residual |w|",
            int(
                np.argmax(np.abs(v) / sigma)
            ): "the largest |v|/σ, not the largest normalised residual |w|",
        }.get(got, "")
        if want == -1:
            why = f"max |w| = {abs(w[i]):.2f} is below k = {k:.2f}: nothing is rejected (return −1)"
        elif got == -1 and w[i] < 0:
            why = f"the largest |w| = {abs(w[i]):.2f} > k belongs to a negative w: test |w|, not w"
        raise CheckFailed(
            f"case {n_case}: got {got}, expected {want}" + (f" — {why}" if why else "")
        )
    success(f"one round of data snooping right in {len(cases)} cases (k = {k:.2f})")


def check_mdb(fn: Callable) -> None:
    """Check ``fn(sigma, r, alpha0, beta0) -> MDB``: δ0 σ / √r, δ0 = z(1 − α0/2) + z(β0)."""
    sigma = np.array([0.005, 0.005, 0.008, 0.003])
    r = np.array([0.25, 0.81, 0.5, 0.12])
    for alpha0, beta0 in ((0.001, 0.80), (0.05, 0.90)):
        d0 = norm.ppf(1 - alpha0 / 2) + norm.ppf(beta0)
        want = d0 * sigma / np.sqrt(r)
        got = call(fn, sigma.copy(), r.copy(), alpha0, beta0, what="mdb")
        compare(
            f"MDB (α0 = {alpha0}, β0 = {beta0})",
            got,
            want,
            rtol=1e-6,
            wrong=[
                ("σ/r: r instead of √r", d0 * sigma / r),
                ("one-sided α0", (norm.ppf(1 - alpha0) + norm.ppf(beta0)) * sigma / np.sqrt(r)),
                ("δ0 without the power term z(β0)", norm.ppf(1 - alpha0 / 2) * sigma / np.sqrt(r)),
                ("σ √r instead of σ / √r", d0 * sigma * np.sqrt(r)),
            ],
        )
    success(f"MDB right; δ0(0.1 %, 80 %) = {norm.ppf(1 - 0.0005) + norm.ppf(0.8):.3f}")


def check_external(fn: Callable) -> None:
    """Check ``fn(A, sigma, i, nabla) -> Δx̂``: what an undetected error ∇ in l_i does to x̂."""
    rng = rng_for("lesson12.check_external")
    A, l, sigma = _line(rng)
    for i, nabla in ((11, 3.0), (4, -2.5)):
        e = np.zeros(len(l))
        e[i] = nabla
        want = _wls(A, l + e, sigma) - _wls(A, l, sigma)  # brute force: adjust twice
        got = call(fn, A.copy(), sigma.copy(), i, nabla, what="external")
        N = A.T @ (A / sigma[:, None] ** 2)
        compare(
            f"Δx̂ for an error in l[{i}]",
            got,
            want,
            rtol=1e-8,
            wrong=[
                ("the weights were forgotten", np.linalg.solve(A.T @ A, A.T @ e)),
                ("N instead of N⁻¹", N @ (A.T @ (e / sigma**2))),
                (
                    "multiplied by AᵀA: the normal matrix is solved with, not multiplied: "
                    "Δx̂ = N⁻¹AᵀPe",
                    (A.T @ A) @ want,
                ),
            ],
        )
    success("the shift of the unknowns by an undetected error is right")


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
