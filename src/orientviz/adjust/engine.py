"""Gauss-Newton / Levenberg-Marquardt least squares: the engine every solver uses.

The engine adjusts the *observation equations* ``l + v = f(x)`` (the functional model)
with weights ``P = diag(1/σ²)``. A problem supplies ``equations(x) -> (f, J)`` with f of shape (n,) and J of shape (n, u)
(dense ndarray or ``scipy.sparse``). The engine iterates

    N Δx = Jᵀ P (l − f),   N = Jᵀ P J (+ λ diag N for Levenberg-Marquardt)

until the corrections are negligible against the parameters' own precision, then
computes σ̂0, the cofactor matrix, redundancy numbers and normalised residuals.
Large block problems use the Schur-complement path in :mod:`orientviz.bundle.reduced`
and return the same :class:`~orientviz.adjust.result.Adjustment`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.linalg
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError
from .loop import Damping, Evaluation, Step, StopRule, iterate
from .rank import raise_if_singular, scaled_condition_bound
from .result import Adjustment, Iteration

F64 = NDArray[np.float64]
Equations = Callable[[F64], tuple[F64, "F64 | sp.spmatrix"]]

#: Dense cofactor matrices are computed up to this many unknowns.
DENSE_LIMIT: int = 3000


def _normal(J, p: F64, r: F64):
    if sp.issparse(J):
        JP = J.T.multiply(p) if hasattr(J.T, "multiply") else J.T @ sp.diags(p)
        JP = sp.csr_matrix(JP)
        return (JP @ J).toarray() if J.shape[1] <= DENSE_LIMIT else sp.csc_matrix(JP @ J), JP @ r
    JP = J.T * p
    return JP @ J, JP @ r


#: A factored normal matrix whose Jacobi-scaled condition number reaches this is treated
#: as singular (diagnosed by :func:`~orientviz.adjust.rank.raise_if_singular`).
COND_LIMIT: float = 1e12


def _well_conditioned(N: F64, c: F64) -> tuple[bool, bool]:
    """Whether the Jacobi-scaled ``N`` has a 2-norm condition number below :data:`COND_LIMIT`
    (``c``: N's upper Cholesky factor, lower triangle zero), and whether the cheap upper
    bound (:func:`~orientviz.adjust.rank.scaled_condition_bound`) proved it. The singular
    values are computed only when the bound is not below half the limit (a margin far
    above the rounding error of either number at that size), so the answer is the one
    ``np.linalg.cond`` of the scaled matrix gives."""
    if scaled_condition_bound(N, (c, False)) < 0.5 * COND_LIMIT:
        return True, True
    d = np.sqrt(np.abs(np.diag(N)))
    d[d == 0] = 1.0
    return bool(np.linalg.cond(N / np.outer(d, d)) < COND_LIMIT), False


def _solve(N, b: F64, names: list[str], context: str, regular: bool = False) -> tuple[F64, bool]:
    """Solve ``N x = b``; return x and whether the condition bound proved N regular.

    ``regular``: N is known to be well-conditioned (the check is skipped). A dense N is
    factored by LAPACK's Cholesky (dpotrf/dpotrs, as ``scipy.linalg.cho_factor`` and
    ``cho_solve`` call them); a singular N raises :class:`NotDeterminableError`.
    """
    if sp.issparse(N):
        from scipy.sparse.linalg import splu

        try:
            return splu(sp.csc_matrix(N)).solve(b), False
        except RuntimeError:
            raise_if_singular(N.toarray(), names, context)
            raise
    c, info = scipy.linalg.lapack.dpotrf(N, lower=0, clean=1)
    if info == 0:
        x, info = scipy.linalg.lapack.dpotrs(c, b, lower=0)
        # guard against near-singular matrices Cholesky happens to factor
        if info == 0 and np.isfinite(x).all():
            if regular:
                return x, False
            ok, by_bound = _well_conditioned(N, c)
            if ok:
                return x, by_bound
    raise_if_singular(N, names, context)
    return np.linalg.lstsq(N, b, rcond=None)[0], False


class _DenseProblem:
    """``l + v = f(x)`` with a dense or sparse Jacobian, for :func:`iterate`.

    The iterate is the parameter vector x (u,); the normal matrix of an evaluation is
    formed once and kept with it (the damped retries of one iteration reuse it).
    """

    def __init__(self, equations, l, p, free_idx, u_all, upd, free_names, context):
        self.equations, self.l, self.p = equations, l, p
        self.free_idx, self.u_all, self.upd = free_idx, u_all, upd
        self.free_names, self.context = free_names, context

    def evaluate(self, x: F64, jacobian: bool) -> Evaluation:
        f, J = self.equations(x)
        r = self.l - f
        cost = float(r @ (self.p * r))
        return Evaluation(cost, bool(np.isfinite(f).all()), {"f": f, "J": J, "r": r})

    def solve(self, x: F64, ev: Evaluation, lam: float, iteration: int) -> Step:
        d = ev.data
        if "N" not in d:
            d["N"], d["b"] = _normal(d["J"][:, self.free_idx], self.p, d["r"])
            if iteration == 1:
                N = d["N"]
                dense = N.toarray() if sp.issparse(N) else N
                if dense.shape[0] <= DENSE_LIMIT:
                    bound = raise_if_singular(dense, self.free_names, self.context)
                    if bound < 0.5 * COND_LIMIT:
                        d["regular_from"] = 0.0
        N, b = d["N"], d["b"]
        diagN = N.diagonal() if sp.issparse(N) else np.diag(N)
        if lam > 0:
            N = N + (sp.diags(lam * diagN) if sp.issparse(N) else np.diag(lam * diagN))
        # N (1 + λ) on the diagonal scales to (M + λ I) / (1 + λ), M the scaled undamped
        # matrix: its condition number falls as λ grows, so a bound that proved N regular
        # at some λ proves it at every larger λ of the same linearisation
        regular = lam >= d.get("regular_from", np.inf)
        dxf, by_bound = _solve(N, b, self.free_names, self.context, regular)
        if by_bound:
            d["regular_from"] = min(lam, d.get("regular_from", np.inf))
        dx = np.zeros(self.u_all)
        dx[self.free_idx] = dxf
        sig_apriori = 1.0 / np.sqrt(np.where(diagN > 0, diagN, np.inf))
        rel = np.abs(dxf) / np.where(sig_apriori > 0, sig_apriori, 1.0)
        return Step(float(rel.max(initial=0.0)), dx, dxf)

    def apply(self, x: F64, step: Step) -> F64:
        return self.upd(x, step.dx)

    def snapshot(self, x: F64) -> F64:
        return x.copy()


def gauss_newton(
    equations: Equations,
    x0: ArrayLike,
    observations: ArrayLike,
    sigma: ArrayLike = 1.0,
    *,
    names: list[str] | None = None,
    groups: dict[str, slice] | None = None,
    obs_labels: list[str] | None = None,
    fixed: ArrayLike | None = None,
    damping: str = "none",
    lambda0: float = 1e-3,
    max_iter: int = 50,
    tol: float = 1e-6,
    xtol: ArrayLike | None = None,
    stop: Callable[[Iteration, Iteration], bool] | None = None,
    update: Callable[[F64, F64], F64] | None = None,
    precision: bool = True,
    context: str = "",
    callback: Callable[[Iteration], object] | None = None,
) -> Adjustment:
    """Adjust ``l + v = f(x)`` by Gauss-Newton, optionally damped (Levenberg-Marquardt).

    Parameters
    ----------
    equations : callable
        ``equations(x) -> (f, J)``, the observation equations: computed observations (n,) and Jacobian (n, u), dense
        or sparse, in the observations' units per parameter unit.
    x0 : array_like, shape (u,)
        Approximate values.
    observations : array_like, shape (n,)
        Observed values l.
    sigma : float or array_like, shape (n,)
        A-priori standard deviations (weights 1/σ²), same units as l.
    names : list of str, optional
        Parameter names for reports and diagnostics (default ``p0, p1, …``).
    groups : dict of str to slice, optional
        Named parameter groups (slices of x), copied into the result.
    obs_labels : list of str, optional
        A label per observation.
    fixed : array_like of bool, shape (u,), optional
        Parameters held at their approximate values.
    damping : {"none", "lm"}
        Pure Gauss-Newton or Levenberg-Marquardt (Marquardt's diagonal scaling).
    lambda0 : float
        Initial λ for ``"lm"``.
    max_iter : int
        Maximum number of steps.
    tol : float
        Stop when every abs(Δx_i) < tol · σ_i, σ_i = √(N⁻¹)_ii the parameter's a-priori
        standard deviation (a parameter-based rule: the step no longer changes anything
        measurable).
    xtol : array_like, shape (u,), optional
        Absolute thresholds per parameter instead of ``tol`` (e.g. 0.5 mm, 1 cc).
    stop : callable, optional
        ``stop(previous, current) -> bool``, a custom stopping rule (e.g. a paper's).
    update : callable, optional
        ``update(x, dx) -> x_new`` (default ``x + dx``).
    precision : bool
        Compute cofactors, redundancy numbers and normalised residuals.
    context : str
        Prefix for error messages (e.g. the task's name).
    callback : callable, optional
        Called with each new :class:`Iteration` (per-step hook).

    Returns
    -------
    Adjustment

    Raises
    ------
    NotDeterminableError
        If the normal matrix is singular; the message names the parameters involved.
    """
    x = np.array(x0, dtype=float).reshape(-1)
    l = np.asarray(observations, dtype=float).reshape(-1)
    n, u_all = l.shape[0], x.shape[0]
    s = np.broadcast_to(np.asarray(sigma, dtype=float), (n,)).copy()
    if not np.all(np.isfinite(s)) or np.any(s <= 0):
        raise InputError("expected positive finite a-priori σ for every observation")
    if not np.all(np.isfinite(x)):
        raise InputError("expected finite approximate values, got NaN or inf")
    if not np.all(np.isfinite(l)):
        raise InputError("expected finite observations, got NaN or inf")
    p = 1.0 / s**2
    names = list(names) if names is not None else [f"p{i}" for i in range(u_all)]
    free = np.ones(u_all, bool) if fixed is None else ~np.asarray(fixed, bool).reshape(-1)
    free_idx = np.flatnonzero(free)
    free_names = [names[i] for i in free_idx]
    upd = update or (lambda a, b: a + b)
    xt = None if xtol is None else np.broadcast_to(np.asarray(xtol, float), (u_all,))[free_idx]

    dof = n - free_idx.size
    problem = _DenseProblem(equations, l, p, free_idx, u_all, upd, free_names, context)
    rule = StopRule(tol=tol, custom=stop)
    if stop is None and xt is not None:
        rule.step_test = lambda step: bool(np.all(np.abs(step.data) <= xt))
    run = iterate(
        problem,
        x,
        redundancy=dof,
        damping=Damping(damping, lambda0=lambda0),
        stop=rule,
        max_iter=max_iter,
        callback=callback,
    )
    x, converged, reason, history = run.state, run.converged, run.reason, run.history
    J, r = run.evaluation.data["J"], run.evaluation.data["r"]

    def s0(c: float) -> float:
        return float(np.sqrt(c / dof)) if dof > 0 else float("nan")

    cost = run.evaluation.cost
    result = Adjustment(
        x=x,
        names=names,
        sigma0=s0(cost),
        redundancy=dof,
        residuals=-r,
        sigma_obs=s,
        converged=converged,
        reason=reason,
        history=history,
        groups=dict(groups or {}),
        obs_labels=obs_labels,
    )
    if precision:
        add_precision(result, J[:, free_idx], p, free_idx, u_all)
    return result


def add_precision(result: Adjustment, Jf, p: F64, free_idx: NDArray[np.int64], u_all: int) -> None:
    """Fill cofactors, redundancy numbers and normalised residuals of a dense problem."""
    if free_idx.size > DENSE_LIMIT:
        return
    Jd = Jf.toarray() if sp.issparse(Jf) else np.asarray(Jf)
    N = (Jd.T * p) @ Jd
    try:
        Qf = scipy.linalg.cho_solve(scipy.linalg.cho_factor(N), np.eye(N.shape[0]))
    except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
        Qf = np.linalg.pinv(N)
    Q = np.zeros((u_all, u_all))
    Q[np.ix_(free_idx, free_idx)] = Qf
    result.cofactor = Q
    # redundancy numbers r_i = 1 − p_i (J Q Jᵀ)_ii, the diagonal from the rows of J Q (one
    # matrix product) instead of a three-operand sum over every (j, k) pair
    h = np.einsum("ij,ij->i", Jd @ Qf, Jd) * p
    rn = np.clip(1.0 - h, 0.0, 1.0)
    result.redundancy_numbers = rn
    with np.errstate(divide="ignore", invalid="ignore"):
        w = result.residuals / (result.sigma_obs * np.sqrt(rn))
    result.normalized_residuals = np.where(rn > 1e-10, w, np.nan)
