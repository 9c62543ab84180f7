"""Gross-error detection: data snooping, robust reweighting, reliability, automatic cleaning.

Data snooping is in :mod:`orientviz.adjust.snooping`; robust reweighting and the rerun
model in :mod:`orientviz.adjust.robust` (``robust_adjust``, ``robust_weights``,
``rerun_cleaning``); both build on the statistics and the cleaning log here.

Everything here works on *any* least-squares problem through one small interface, a
**solver** ``solve(weights) -> Adjustment``: ``weights`` (n,) are factors on the a-priori
weights of the n observations (1 = as given, 0 = eliminated, in between = down-weighted)
and the returned :class:`~orientviz.adjust.result.Adjustment` reports residuals,
redundancy numbers and normalised residuals for all n observations (eliminated ones get
redundancy number 0 and a NaN normalised residual). :func:`engine_solver` builds such a
solver for a problem of :func:`orientviz.adjust.gauss_newton`; the block bundle gets one in
:mod:`orientviz.bundle`.

Statistics (Baarda 1968, a-priori σ0 = 1):

* normalised residual ``w_i = v_i / (σ_i √r_i)`` with the redundancy number
  ``r_i = (Q_vv P)_ii``; without gross errors ``w_i ~ N(0, 1)``;
* the w-test rejects at ``|w_i| > k = z(1 − α0/2)`` (α0 = 0.1 % → k = 3.29);
* non-centrality ``δ0 = z(1 − α0/2) + z(β0)`` (β0 = 80 % power → δ0 = 4.13);
* internal reliability, the minimal detectable bias ``∇_i = δ0 σ_i / √r_i``;
* external reliability ``δ̄0_i = δ0 √((1 − r_i)/r_i)``, and the effect of an
  undetected ``∇_i`` on the parameters ``Δx = Q_xx J_iᵀ p_i ∇_i``.

Observations can be tested in **groups** (e.g. the x and y coordinate of one image ray):
a group's statistic is the largest abs(w_i) of its members, and a group is eliminated
as a whole.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import AdjustmentError, InputError, NotDeterminableError
from .engine import gauss_newton
from .result import Adjustment

F64 = NDArray[np.float64]
Solver = Callable[[F64], Adjustment]

__all__ = [
    "Cleaning",
    "CleaningBreakdown",
    "LogEntry",
    "Reliability",
    "critical_value",
    "engine_solver",
    "noncentrality",
    "redundancy_numbers",
    "reliability",
]


# --------------------------------------------------------------------------- test values
def critical_value(alpha0: float = 0.001) -> float:
    """Critical value of the two-sided w-test, ``k = z(1 − α0/2)`` (α0 = 0.001 → 3.29)."""
    if not 0.0 < alpha0 < 1.0:
        raise InputError(f"expected a significance level 0 < alpha0 < 1, got {alpha0}")
    from scipy.special import ndtri  # scipy.special loads many modules: not at the package's import

    return float(ndtri(1.0 - alpha0 / 2.0))


def noncentrality(alpha0: float = 0.001, beta0: float = 0.80) -> float:
    """Baarda's non-centrality ``δ0 = z(1 − α0/2) + z(β0)`` (0.1 %, 80 % → 4.13).

    Parameters
    ----------
    alpha0 : float
        Significance level of the one-dimensional w-test.
    beta0 : float
        Power: probability that a bias of size δ0 (in units of its σ) is detected.
    """
    if not 0.0 < beta0 < 1.0:
        raise InputError(f"expected a power 0 < beta0 < 1, got {beta0}")
    from scipy.special import ndtri  # as in critical_value

    return critical_value(alpha0) + float(ndtri(beta0))


def redundancy_numbers(J: ArrayLike, sigma: ArrayLike) -> F64:
    """Redundancy numbers ``r_i = 1 − p_i (J N⁻¹ Jᵀ)_ii`` of a dense linear(ised) model.

    Parameters
    ----------
    J : array_like, shape (n, u)
        Jacobian (design matrix), observation units per parameter unit.
    sigma : float or array_like, shape (n,)
        A-priori σ of the observations (same units as the rows of J).

    Returns
    -------
    ndarray, shape (n,)
        Values in [0, 1] summing to n − u (0: the observation is not controlled).
    """
    J = np.asarray(J, dtype=float)
    p = 1.0 / np.broadcast_to(np.asarray(sigma, float), (J.shape[0],)) ** 2
    N = (J.T * p) @ J
    try:
        Q = np.linalg.inv(N)
    except np.linalg.LinAlgError:
        raise NotDeterminableError("the design matrix has a rank defect") from None
    h = np.einsum("ij,jk,ik->i", J, Q, J) * p
    return np.clip(1.0 - h, 0.0, 1.0)


@dataclass
class Reliability:
    """Internal and external reliability per observation (Baarda).

    Attributes
    ----------
    redundancy_numbers : ndarray, shape (n,)
        r_i in [0, 1].
    mdb : ndarray, shape (n,)
        Minimal detectable bias ∇_i = δ0 σ_i / √r_i, observation units (inf if r_i = 0).
    external : ndarray, shape (n,)
        δ̄0_i = δ0 √((1 − r_i) / r_i), dimensionless: the largest effect of an undetected
        ∇_i on any function of the parameters, in units of that function's σ.
    effect : ndarray, shape (n, u) or None
        Δx caused by ∇_i on each parameter (parameter units), when J and Q_xx are known.
    alpha0, beta0, critical, delta0 : float
        Test parameters: level, power, critical value k and non-centrality δ0.
    """

    redundancy_numbers: F64
    mdb: F64
    external: F64
    effect: F64 | None
    alpha0: float
    beta0: float
    critical: float
    delta0: float


def reliability(
    adj: Adjustment, J: ArrayLike | None = None, *, alpha0: float = 0.001, beta0: float = 0.80
) -> Reliability:
    """Reliability of every observation of an adjustment.

    Parameters
    ----------
    adj : Adjustment
        Needs ``redundancy_numbers`` and ``sigma_obs``; for ``effect`` also ``cofactor``.
    J : array_like, shape (n, u), optional
        The Jacobian at the solution (all parameters, fixed ones included as zero columns
        or not: only columns with non-zero cofactor rows matter).
    alpha0, beta0 : float
        Test level and power (defaults 0.1 %, 80 %).
    """
    if adj.redundancy_numbers is None:
        raise InputError("the adjustment carries no redundancy numbers (precision=False?)")
    r = np.asarray(adj.redundancy_numbers, float)
    d0 = noncentrality(alpha0, beta0)
    with np.errstate(divide="ignore", invalid="ignore"):
        mdb = np.where(r > 1e-10, d0 * adj.sigma_obs / np.sqrt(r), np.inf)
        ext = np.where(r > 1e-10, d0 * np.sqrt((1.0 - r) / r), np.inf)
    effect = None
    if J is not None and adj.cofactor is not None:
        Jd = np.asarray(J, float)
        p = 1.0 / adj.sigma_obs**2
        fin = np.where(np.isfinite(mdb), mdb, 0.0)
        effect = (Jd * (p * fin)[:, None]) @ adj.cofactor.T
    return Reliability(r, mdb, ext, effect, alpha0, beta0, critical_value(alpha0), d0)


# --------------------------------------------------------------------------- solvers
def engine_solver(
    equations: Callable[[F64], tuple[F64, F64]],
    x0: ArrayLike,
    observations: ArrayLike,
    sigma: ArrayLike = 1.0,
    *,
    warm_start: bool = False,
    **options,
) -> Solver:
    """A solver ``solve(weights) -> Adjustment`` for a :func:`gauss_newton` problem.

    Eliminated observations (weight 0) are dropped from the adjustment; their residuals
    ``f(x̂) − l`` are still reported, with redundancy number 0 and normalised residual NaN.
    Down-weighted ones get ``σ_i / √w_i``; ``sigma_obs`` of the result is always the
    a-priori σ (so that normalised residuals keep their meaning).

    Parameters
    ----------
    equations, x0, observations, sigma
        As for :func:`orientviz.adjust.gauss_newton`.
    warm_start : bool
        Start each solve from the previous solution (faster, for well-behaved problems).
    **options
        Passed to :func:`gauss_newton` (``names``, ``fixed``, ``damping``, …).
    """
    l = np.asarray(observations, float).reshape(-1)
    n = l.shape[0]
    s = np.broadcast_to(np.asarray(sigma, float), (n,)).copy()
    start = {"x": np.asarray(x0, float).reshape(-1).copy()}

    def solve(weights: F64) -> Adjustment:
        w = np.broadcast_to(np.asarray(weights, float), (n,))
        keep = w > 0
        idx = np.flatnonzero(keep)

        def sub(x):
            f, J = equations(x)
            return f[idx], J[idx]

        adj = gauss_newton(sub, start["x"], l[idx], s[idx] / np.sqrt(w[idx]), **options)
        if warm_start and adj.converged:
            start["x"] = adj.x.copy()
        f, _ = equations(adj.x)
        rn = np.zeros(n)
        wn = np.full(n, np.nan)
        if adj.redundancy_numbers is not None:
            rn[idx] = adj.redundancy_numbers
            with np.errstate(divide="ignore", invalid="ignore"):
                wn[idx] = np.where(
                    rn[idx] > 1e-10, (f[idx] - l[idx]) / (s[idx] * np.sqrt(rn[idx])), np.nan
                )
        return replace(
            adj, residuals=f - l, sigma_obs=s.copy(), redundancy_numbers=rn, normalized_residuals=wn
        )

    return solve


# --------------------------------------------------------------------------- log
@dataclass
class LogEntry:
    """One decision of an automatic cleaning run.

    Attributes
    ----------
    observation : int
        The observation (or group, e.g. image ray) concerned.
    label : str
        Its label for reports.
    w : float
        Its test statistic at the decision: the largest absolute normalised residual of
        the group, or √T of the 2-D test (equal to abs(w) with one degree of freedom).
    iteration : int
        Number of the adjustment after which the decision was taken (1 = the first).
    action : str
        ``"eliminated"``, ``"kept"``, ``"down-weighted"``, ``"stopped"`` or ``"breakdown"``.
    reason : str
        Why, in words.
    """

    observation: int
    label: str
    w: float
    iteration: int
    action: str
    reason: str


@dataclass
class Cleaning:
    """Result of an automatic cleaning run.

    Attributes
    ----------
    adjustment : Adjustment
        The final adjustment (without the eliminated observations).
    weights : ndarray, shape (n,)
        Final weight factors per observation (0 = eliminated).
    eliminated : ndarray of int
        Eliminated groups (observation indices if no groups were given), in order.
    log : list of LogEntry
        Every decision.
    adjustments : int
        How many adjustments were computed.
    method : str
        ``"data snooping"``, ``"robust (huber)"``, ``"robust (danish)"``, ``"reruns"``.
    """

    adjustment: Adjustment
    weights: F64
    eliminated: NDArray[np.int64]
    log: list[LogEntry] = field(default_factory=list)
    adjustments: int = 0
    method: str = ""

    def table(self) -> str:
        """The log as a plain-text table."""
        lines = [f"{'iter':>4}  {'obs':>6}  {'label':<18} {'|w|,√T':>7}  action"]
        for e in self.log:
            lines.append(
                f"{e.iteration:>4}  {e.observation:>6}  {e.label:<18} {e.w:7.2f}  "
                f"{e.action}: {e.reason}"
            )
        return "\n".join(lines)


class CleaningBreakdown(AdjustmentError):
    """The cleaning could not reach a consistent adjustment; ``log`` keeps what was done."""

    def __init__(self, message: str, log: list[LogEntry], weights: F64):
        self.log = log
        self.weights = weights
        super().__init__(message)


def _groups(n: int, groups: ArrayLike | None) -> tuple[NDArray[np.int64], int]:
    if groups is None:
        return np.arange(n), n
    g = np.asarray(groups, dtype=np.int64).reshape(-1)
    if g.shape != (n,) or (n and g.min() < 0):
        raise InputError(f"groups: expected {n} non-negative group indices, got shape {g.shape}")
    return g, int(g.max()) + 1 if n else 0


def _labels(labels: list[str] | None, ng: int) -> list[str]:
    return list(labels) if labels is not None else [f"obs{i}" for i in range(ng)]


def _check_converged(adj, log, weights, it):
    if not adj.converged or not np.isfinite(adj.sigma0):
        log.append(LogEntry(-1, "", float("nan"), it, "breakdown", adj.reason))
        raise CleaningBreakdown(
            f"the adjustment broke down after {it} adjustment(s) ({adj.reason}); "
            f"{len(log)} decision(s) are kept in the log",
            log,
            weights,
        )
