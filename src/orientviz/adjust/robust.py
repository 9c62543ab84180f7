"""Robust adjustment (Huber, the Danish method) and the rerun model of manual cleaning.

Both work on a solver ``solve(weights) -> Adjustment`` like everything in
:mod:`orientviz.adjust.gross` (where they are also importable from) and return a
:class:`~orientviz.adjust.gross.Cleaning` with its log.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError
from .gross import (
    Cleaning,
    CleaningBreakdown,
    LogEntry,
    Solver,
    _check_converged,
    _groups,
    _labels,
    critical_value,
)

F64 = NDArray[np.float64]

__all__ = ["rerun_cleaning", "robust_adjust", "robust_weights"]


# --------------------------------------------------------------------------- robust
def robust_weights(e: ArrayLike, method: str = "danish", c: float | None = None) -> F64:
    """Weight factors of iteratively reweighted least squares for standardised residuals.

    Parameters
    ----------
    e : array_like
        Standardised residuals (dimensionless, ~N(0, 1) for good observations).
    method : {"huber", "danish"}
        ``"huber"``: w = 1 for abs(e) ≤ c, c/abs(e) beyond (c = 1.5): bounded influence.
        ``"danish"`` (Krarup's Danish method, a continuous form): w = 1 for abs(e) ≤ c,
        ``exp(1 − (|e|/c)²)`` beyond (c = 3): large errors lose their weight
        (influence redescends to 0).
    c : float, optional
        Tuning constant (defaults above).
    """
    a = np.abs(np.nan_to_num(np.asarray(e, float), nan=0.0))
    if method == "huber":
        c = 1.5 if c is None else c
        return np.where(a <= c, 1.0, c / np.maximum(a, 1e-300))
    if method == "danish":
        c = 3.0 if c is None else c
        return np.where(a <= c, 1.0, np.exp(np.clip(1.0 - (a / c) ** 2, -700.0, 0.0)))
    raise InputError(f"unknown robust method {method!r}; expected 'huber' or 'danish'")


def robust_adjust(
    solve: Solver,
    n: int,
    *,
    method: str = "danish",
    c: float | None = None,
    alpha0: float = 0.001,
    groups: ArrayLike | None = None,
    labels: list[str] | None = None,
    max_iter: int = 30,
    tol: float = 1e-3,
    max_fraction: float = 0.2,
    reinstate: bool = True,
) -> Cleaning:
    """Robust adjustment by iteratively reweighted least squares, then a clean final run.

    Iteration: adjust, standardise each residual with the *first* adjustment's redundancy
    numbers, ``e_i = v_i / (σ_i √r_i)``, take a group's largest abs(e) for all its members,
    set weight factors ``robust_weights(e)``, repeat until the factors change by less than
    ``tol``. Groups with abs(e) > k = z(1 − α0/2) at the end are declared gross errors,
    eliminated, and a final ordinary adjustment without them gives σ0 and the precision.

    Parameters
    ----------
    solve, n, alpha0, groups, labels, max_fraction
        As in :func:`data_snooping`.
    method, c
        Weight function and tuning constant (:func:`robust_weights`).
    max_iter, tol
        Limits of the reweighting loop.
    reinstate : bool
        After the final run, put back rejected groups whose predicted residual (from the
        adjustment without the rejected ones) is below k σ, and adjust once more.
    """
    g, ng = _groups(n, groups)
    names = _labels(labels, ng)
    k = critical_value(alpha0)
    wts = np.ones(n)
    log: list[LogEntry] = []
    adj = solve(wts)
    _check_converged(adj, log, wts, 1)
    r0 = np.asarray(adj.redundancy_numbers, float)
    count = 1
    e_g = np.zeros(ng)
    for it in range(2, max_iter + 2):
        with np.errstate(divide="ignore", invalid="ignore"):
            e = np.where(r0 > 1e-10, adj.residuals / (adj.sigma_obs * np.sqrt(r0)), 0.0)
        e_g = np.zeros(ng)
        np.maximum.at(e_g, g, np.abs(e))
        new = robust_weights(e_g, method, c)[g]
        change = float(np.max(np.abs(new - wts), initial=0.0))
        wts = new
        if change < tol:
            break
        adj = solve(wts)
        count += 1
        _check_converged(adj, log, wts, it)
    bad = np.flatnonzero(e_g > k)  # groups: their largest |e|
    bad = bad[np.argsort(-e_g[bad])]
    if bad.size > max_fraction * ng:
        raise CleaningBreakdown(
            f"robust adjustment marks {bad.size} of {ng} observations as gross errors "
            f"(> {max_fraction:.0%}); the data are too contaminated for automatic cleaning",
            log,
            wts,
        )
    final = np.ones(n)
    for b in bad:
        final[g == b] = 0.0
        log.append(
            LogEntry(
                int(b),
                names[b],
                float(e_g[b]),
                count,
                "eliminated",
                f"robust |e| = {e_g[b]:.2f} > k = {k:.2f}, weight fell to "
                f"{float(robust_weights(e_g[b : b + 1], method, c)[0]):.2g}",
            )
        )
    adj = solve(final)
    count += 1
    _check_converged(adj, log, final, count)
    if reinstate and bad.size:
        # predicted residuals of the rejected groups from the clean adjustment: a group
        # whose |v| / σ stays below k was only dragged along by a neighbouring blunder
        # (|v|/σ ignores the σ of the prediction: conservative, reinstates fewer)
        with np.errstate(invalid="ignore"):
            a = np.abs(np.nan_to_num(adj.residuals / adj.sigma_obs, nan=np.inf))
        p_g = np.zeros(ng)
        np.maximum.at(p_g, g, a)
        back = bad[p_g[bad] <= k]
        if back.size:
            for b in back:
                final[g == b] = 1.0
                log.append(
                    LogEntry(int(b), names[b], float(p_g[b]), count, "reinstated",
                             f"predicted |v|/σ = {p_g[b]:.2f} ≤ k without the gross errors")
                )  # fmt: skip
            bad = np.setdiff1d(bad, back, assume_unique=True)
            bad = bad[np.argsort(-e_g[bad])]
            adj = solve(final)
            count += 1
            _check_converged(adj, log, final, count)
    log.append(LogEntry(-1, "", 0.0, count, "stopped", "final adjustment without gross errors"))
    return Cleaning(adj, final, bad.astype(np.int64), log, count, f"robust ({method})")


# --------------------------------------------------------------------------- manual practice
def rerun_cleaning(
    solve: Solver,
    n: int,
    *,
    threshold: float = 3.0,
    groups: ArrayLike | None = None,
    labels: list[str] | None = None,
    max_runs: int = 20,
) -> Cleaning:
    """The manual practice of the 1970s (Ackermann §13: 3 to 6 reruns): a model of it.

    Each *run* is one adjustment; after it the operator removes every (group of)
    observation(s) whose raw residual exceeds ``threshold · σ̂0 · σ_i`` (σ̂0 of that run,
    inflated by the blunders still present; no redundancy numbers — programs of the time
    printed residuals, not normalised residuals) and starts the next run, until a run
    flags nothing. Returns the runs needed and what was removed (including good
    observations removed by mistake).
    """
    g, ng = _groups(n, groups)
    names = _labels(labels, ng)
    wts = np.ones(n)
    log: list[LogEntry] = []
    eliminated: list[int] = []
    for run in range(1, max_runs + 1):
        adj = solve(wts)
        _check_converged(adj, log, wts, run)
        e = np.abs(adj.residuals) / (adj.sigma_obs * max(adj.sigma0, 1e-300))
        e[wts == 0] = 0.0
        e_g = np.zeros(ng)
        np.maximum.at(e_g, g, e)
        bad = np.flatnonzero(e_g > threshold)
        if bad.size == 0:
            log.append(LogEntry(-1, "", 0.0, run, "stopped", "no residual above the threshold"))
            break
        for b in bad:
            wts[g == b] = 0.0
            eliminated.append(int(b))
            log.append(
                LogEntry(
                    int(b),
                    names[b],
                    float(e_g[b]),
                    run,
                    "eliminated",
                    f"|v| = {e_g[b]:.1f} σ̂0 > {threshold:g} σ̂0 (σ̂0 = {adj.sigma0:.3g})",
                )
            )
    return Cleaning(adj, wts, np.array(eliminated, dtype=np.int64), log, run, "reruns")
