"""Baarda's data snooping: test, eliminate the worst, re-adjust, repeat.

Works on a solver ``solve(weights) -> Adjustment`` like everything in
:mod:`orientviz.adjust.gross` (where :func:`data_snooping` is importable from as well);
tests are the w-test or the 2-D test of image points (:mod:`orientviz.adjust.gross2d`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError, NotDeterminableError
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
from .gross2d import critical_values_2d, statistic_2d
from .result import Adjustment

F64 = NDArray[np.float64]

__all__ = ["data_snooping"]


def _group_stat(adj: Adjustment, g: NDArray[np.int64], ng: int) -> tuple[F64, F64]:
    """Per group: the largest w² (the w-test) and Σ w² (to rank groups of several members).

    NaN (uncontrolled or eliminated) members count as 0.
    """
    if adj.normalized_residuals is None:
        raise InputError("the solver returned no normalised residuals; cannot test")
    w = np.abs(np.nan_to_num(np.asarray(adj.normalized_residuals, float), nan=0.0))
    mx = np.zeros(ng)
    np.maximum.at(mx, g, w * w)
    return mx, np.bincount(g, weights=w * w, minlength=ng)


def _statistics(adj: Adjustment, g, ng: int, test: str, crit: dict[int, float]):
    """Test value T, its critical value, ranking value and dof per group."""
    if test == "w":
        T, rank = _group_stat(adj, g, ng)
        return T, np.full(ng, crit[1]), rank, np.ones(ng, np.int64)

    rxy = adj.redundancy_xy
    if rxy is None or adj.normalized_residuals is None:
        raise InputError("the 2-D test needs normalised residuals and redundancy_xy")
    r = np.nan_to_num(np.asarray(adj.redundancy_numbers, float))
    z = np.nan_to_num(np.asarray(adj.normalized_residuals, float)) * np.sqrt(r)
    T, dof = statistic_2d(z.reshape(-1, 2), r.reshape(-1, 2), np.nan_to_num(rxy))
    cv = np.array([crit[0], crit[1], crit[2]])[dof]
    return T, cv, T.copy(), dof


def _select(stat: F64, rank: F64, k: F64, clusters: list[NDArray[np.int64]] | None) -> F64:
    """Groups to eliminate now: the worst one, or every local worst one of the clusters."""
    cand = np.flatnonzero(stat > k)
    if cand.size == 0:
        return cand
    if clusters is None:
        return cand[[int(np.argmax(rank[cand]))]]
    ok = np.ones(cand.size, bool)
    for cl in clusters:
        best = np.full(int(cl.max()) + 1, -1.0)
        np.maximum.at(best, cl[cand], rank[cand])
        ok &= rank[cand] >= best[cl[cand]]
    sel = cand[ok]
    return sel[np.argsort(-rank[sel])]


def _partners(batch, stat, crit, rank, key, margin: float) -> list[tuple[int, int]]:
    """(a, b): group b shares a's key, is rejected too and fits almost as well (not separable)."""
    out: list[tuple[int, int]] = []
    if key is None or margin <= 0:
        return out
    chosen = set(int(a) for a in batch)
    rej = np.flatnonzero(stat > crit)
    rej = rej[np.argsort(key[rej], kind="stable")]  # rejected groups by key, index order
    rkey = key[rej]
    for a in batch:
        same = rej[np.searchsorted(rkey, key[a]) : np.searchsorted(rkey, key[a], "right")]
        for b in same:
            if int(b) not in chosen and rank[a] - rank[b] < margin:
                chosen.add(int(b))
                out.append((int(a), int(b)))
    return out


def data_snooping(
    solve: Solver,
    n: int,
    *,
    alpha0: float = 0.001,
    beta0: float = 0.80,
    groups: ArrayLike | None = None,
    labels: list[str] | None = None,
    max_fraction: float = 0.2,
    weights: ArrayLike | None = None,
    clusters: list[ArrayLike] | None = None,
    test: str = "w",
    separate: ArrayLike | None = None,
    separation: float = 0.0,
    solve_exact: Solver | None = None,
    exact_first: bool = False,
    exact_when_few: float = 0.0,
) -> Cleaning:
    """Baarda's data snooping: eliminate the worst observation, re-adjust, repeat.

    Each adjustment tests every (group of) observation(s); if some test value exceeds
    its critical value the worst group — and only that one, because a blunder spreads
    into the residuals of its neighbours — is eliminated and the adjustment is repeated,
    until no test rejects.

    Tests (``test``):

    * ``"w"``: the w-test of each observation, ``abs(w) > k = z(1 − α0/2)``; a group is
      tested by its largest w² and ranked by Σ w² of its members;
    * ``"2d"``: observations come in (x, y) pairs ``2i, 2i + 1`` (one group per pair);
      each pair is tested with the 2-D statistic T = zᵀR⁻¹z
      (:func:`orientviz.adjust.gross2d.statistic_2d`; the solver's Adjustment must
      carry ``redundancy_xy`` (n/2,)) against the B-method critical value of
      its rank (1 or 2 dof, common power β0) and ranked by T, the decrease of vᵀPv
      when the pair is left out.

    With ``clusters`` several groups can go in one adjustment: every rejected group that
    is the worst of each of its clusters (e.g. for image rays: the worst ray of its point
    *and* of its image) — blunders far apart do not mask each other, so this takes far
    fewer adjustments on large blocks and is otherwise the same test.

    With ``separate`` (a key per group, e.g. the point of a ray) and ``separation`` > 0
    a rejected group's rejected partners of the same key whose ranking value is less
    than ``separation`` below it go too: the data cannot tell which of them is wrong
    (with the 2-D test the ranking difference is twice the log-likelihood ratio of the
    two hypotheses). A 3-ray tie point of one strip, for instance, has a single
    redundancy along the base: an error there gives all three rays the same statistic.

    Parameters
    ----------
    solve : callable
        ``solve(weights) -> Adjustment`` (see module docstring).
    n : int
        Number of observations.
    alpha0, beta0 : float
        Level of the 1-D test (default 0.1 %, k = 3.29) and the power that fixes the
        level of the 2-D test (B-method, default 80 %).
    groups : array_like of int, shape (n,), optional
        Group index per observation (tested and eliminated together).
    labels : list of str, optional
        Label per group for the log.
    max_fraction : float
        Stop with :class:`CleaningBreakdown` if more than this fraction of the groups
        would have to be eliminated: the data are then too bad to clean automatically.
    weights : array_like, shape (n,), optional
        Starting weight factors (default all 1).
    clusters : list of array_like of int, each shape (n_groups,), optional
        Cluster keys per group (see above); None: one group per adjustment (Baarda).
    test : {"w", "2d"}
        Test statistic (see above).
    separate : array_like of int, shape (n_groups,), optional
        Key per group within which rejections must be separable.
    separation : float
        Margin of the ranking value (dimensionless, a χ² difference); 0: off.
    solve_exact : callable, optional
        If given, ``solve`` may be a cheaper solver whose statistics never exceed the
        exact ones (e.g. redundancy numbers from a local model): when its tests reject
        nothing, the adjustment is repeated with ``solve_exact`` and tested again, and
        the run ends only when an exact adjustment rejects nothing.
    exact_first : bool
        With ``solve_exact``: the first adjustment is exact too (a solver may then
        use its redundancy numbers to sharpen the later screening rounds, as
        :func:`orientviz.bundle.bundle_solver` does).
    exact_when_few : float
        With ``solve_exact``: after an adjustment that eliminated fewer groups than this
        fraction of the most any adjustment has eliminated, the next one is exact at once
        (near the end a screening round mostly finds nothing and only delays the exact
        one; default 0: screening after every elimination).

    Returns
    -------
    Cleaning

    Raises
    ------
    CleaningBreakdown
        The adjustment diverged or too many observations were rejected; ``.log`` keeps
        every decision so far.
    """
    if test not in ("w", "2d"):
        raise InputError(f"unknown test {test!r}; expected 'w' or '2d'")
    g, ng = _groups(n, groups)
    if test == "2d" and (n % 2 or np.any(g[0::2] != g[1::2]) or np.unique(g).size != n // 2):
        raise InputError("the 2-D test needs (x, y) pairs 2i, 2i + 1 as the groups")
    names = _labels(labels, ng)
    if test == "2d":
        crit = critical_values_2d(alpha0, beta0)
    else:
        crit = {0: np.inf, 1: critical_value(alpha0) ** 2, 2: np.inf}
    cl = None if clusters is None else [np.asarray(c, np.int64).reshape(-1) for c in clusters]
    if cl is not None and any(c.shape != (ng,) or (ng and c.min() < 0) for c in cl):
        raise InputError(f"clusters: expected arrays of {ng} non-negative keys (one per group)")
    key = None if separate is None else np.asarray(separate, np.int64).reshape(-1)
    if key is not None and key.shape != (ng,):
        raise InputError(f"separate: expected {ng} keys (one per group), got {key.shape}")
    wts = np.ones(n) if weights is None else np.asarray(weights, float).copy()
    by_group = np.argsort(g, kind="stable")
    g_start = np.searchsorted(g[by_group], np.arange(ng + 1))

    def members(b: int) -> NDArray[np.int64]:
        return by_group[g_start[b] : g_start[b + 1]]

    active = np.ones(ng, bool)
    active[np.setdiff1d(np.arange(ng), g[wts > 0])] = False
    log: list[LogEntry] = []
    eliminated: list[int] = []
    last_batch: list[int] = []
    protected = np.zeros(ng, bool)
    it = 0
    exact = solve_exact is None or exact_first
    most = 0

    def why(b, T, cv, dof):
        if test == "w":
            return f"|w| = {np.sqrt(T[b]):.2f} > k = {np.sqrt(cv[b]):.2f} (α0 = {alpha0:g})"
        return (
            f"T = {T[b]:.1f} > {cv[b]:.2f} ({dof[b]} dof, B-method α0 = {alpha0:g}, β0 = {beta0:g})"
        )

    while True:
        it += 1
        try:
            adj = solve(wts) if solve_exact is None or not exact else solve_exact(wts)
        except NotDeterminableError as exc:
            if not last_batch:
                raise
            # the last elimination took away the only control of some parameters: undo it
            for last in last_batch:
                eliminated.remove(last)
                wts[members(last)] = 1.0
                active[last] = True
                protected[last] = True
                log.append(
                    LogEntry(last, names[last], float("nan"), it, "kept", f"removal leaves {exc}")
                )
            last_batch = []
            continue
        _check_converged(adj, log, wts, it)
        T, cv, rank, dof = _statistics(adj, g, ng, test, crit)
        off = ~active | protected
        T[off] = 0.0
        rank[off] = 0.0
        batch = _select(T, rank, cv, cl) if ng else np.zeros(0, np.int64)
        if batch.size == 0 and not exact:
            exact = True  # the cheap tests are satisfied: check with the exact ones
            continue
        if batch.size == 0:
            worst = int(np.argmax(T / cv)) if ng else 0
            top = float(np.sqrt(T[worst])) if ng else 0.0
            log.append(
                LogEntry(worst, names[worst] if ng else "", top, it, "stopped",
                         "no test rejects (largest " + (f"|w| = {top:.2f})" if test == "w"
                         else f"T = {top**2:.1f} ≤ {cv[worst]:.2f})"))
            )  # fmt: skip
            break
        pairs = _partners(batch, T, cv, rank, key, separation)
        if len(eliminated) + batch.size + len(pairs) > max_fraction * ng:
            b0 = int(batch[0])
            log.append(LogEntry(b0, names[b0], float(np.sqrt(T[b0])), it, "breakdown", ""))
            raise CleaningBreakdown(
                f"data snooping would eliminate more than {max_fraction:.0%} of the "
                f"{ng} observations (still {why(b0, T, cv, dof)}); the data are "
                f"too contaminated for automatic cleaning — the log keeps "
                f"{len(eliminated)} eliminations",
                log,
                wts,
            )
        last_batch = [int(b) for b in batch] + [b for _, b in pairs]
        most = max(most, len(last_batch))
        exact = solve_exact is None or len(last_batch) < exact_when_few * most
        for b in last_batch:
            eliminated.append(b)
            active[b] = False
            wts[members(b)] = 0.0
        for b in batch:
            log.append(
                LogEntry(int(b), names[b], float(np.sqrt(T[b])), it, "eliminated", why(b, T, cv, dof))
            )  # fmt: skip
        for a, b in pairs:
            log.append(
                LogEntry(b, names[b], float(np.sqrt(T[b])), it, "eliminated",
                         f"{why(b, T, cv, dof)}; not separable from {names[a]} "
                         f"(ranking {rank[a]:.1f} vs {rank[b]:.1f}, margin {separation:g})")
            )  # fmt: skip
    return Cleaning(adj, wts, np.array(eliminated, dtype=np.int64), log, it, "data snooping")
