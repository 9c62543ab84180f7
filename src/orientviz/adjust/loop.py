"""The one Gauss-Newton / Levenberg-Marquardt loop of orientviz.

Every adjustment iterates here: the dense engine (:func:`orientviz.adjust.gauss_newton`)
and the bundle (:func:`orientviz.bundle.bundle_adjust`). A problem supplies, for an
iterate it owns (any immutable value):

* ``evaluate(state, jacobian) -> Evaluation`` — vᵀPv at ``state`` and, if asked, what
  its normal equations need (derivatives);
* ``solve(state, evaluation, lam, iteration) -> Step`` — the correction from the normal
  equations damped by λ (diagonal × (1 + λ) or + λ·diag), with its size in units of the
  parameters' a-priori σ; raises :class:`~orientviz.errors.NotDeterminableError` when
  they are singular;
* ``apply(state, step) -> state`` — the next iterate;
* ``snapshot(state) -> ndarray`` — the parameters for the history (may be empty).

The loop owns damping, acceptance and stopping, records one
:class:`~orientviz.adjust.result.Iteration` per step and calls ``callback`` with it (the
viewer's scrubber, a notebook's live plot). Damping policies (:class:`Damping`):

* ``"none"`` — pure Gauss-Newton: every step is taken;
* ``"lm"`` — Levenberg-Marquardt from λ0: λ × 10 until vᵀPv decreases, then λ / 10;
* ``"trust"`` — Levenberg-Marquardt as a trust region (Ceres's schedule for steps that
  realise their model's decrease: Ceres shrinks λ by max(1/3, 1 − (2ρ − 1)³), ρ the gain
  ratio, this loop by 3 whatever ρ): λ starts at λ0 (1e-4), a step that decreases vᵀPv
  is taken and λ shrinks by 3 (never below 1e-16: the damping stays, so a weakly
  determined far point moves only as far as its rays' misclosures pull it in one step);
  a step that does not is retried with λ × ν, ν doubling (2, 4, 8, …) until it does
  (λ > 1e16: damping exhausted). A system that is singular after the first iteration
  (numerically: weak parameters, down-weighted rays) is a rejected step too, retried
  with λ at least λ0;
* ``"fallback"`` — Gauss-Newton while vᵀPv does not increase; a step that would
  increase it is retried with λ = max(10 λ, 1e-4) until it does not (λ > 1e8: damping
  exhausted), and λ goes back by / 10 per accepted step (to 0 below 1e-6). A singular
  system is retried damped (λ ≥ 1e-3) when the start is poor (σ0 ≥
  ``poor_start_sigma0``); the caller then checks the undamped system at the solution.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError, NotDeterminableError
from .result import Iteration

F64 = NDArray[np.float64]
#: ``"trust"`` damping: λ stays at or above this (Ceres's largest trust region, 1e16).
TRUST_MIN_LAMBDA: float = 1e-16
DAMPING_KINDS = ("none", "lm", "fallback", "trust")


@dataclass
class Evaluation:
    """A problem's evaluation at one iterate.

    Attributes
    ----------
    cost : float
        vᵀPv.
    finite : bool
        Whether the observation equations are defined there (no NaN/inf).
    data : object
        What the problem needs to form its normal equations (opaque to the loop).
    """

    cost: float
    finite: bool = True
    data: Any = None


@dataclass
class Step:
    """A correction computed by a problem.

    Attributes
    ----------
    max_correction : float
        max abs(dx_i) / σ_i over the estimated parameters (σ_i a-priori).
    dx : ndarray or None
        The correction for the history (same layout as the snapshot), or None.
    data : object
        The correction in the problem's own form (opaque to the loop).
    """

    max_correction: float
    dx: F64 | None = None
    data: Any = None


class IterativeProblem(Protocol):
    """What the loop asks of a problem (see the module docstring)."""

    def evaluate(self, state: Any, jacobian: bool) -> Evaluation: ...

    def solve(self, state: Any, ev: Evaluation, lam: float, iteration: int) -> Step: ...

    def apply(self, state: Any, step: Step) -> Any: ...

    def snapshot(self, state: Any) -> F64: ...


@dataclass(frozen=True)
class Damping:
    """How the loop damps and accepts steps.

    Attributes
    ----------
    kind : {"none", "lm", "fallback"}
        See the module docstring.
    lambda0 : float
        Initial λ of ``"lm"``.
    poor_start_sigma0 : float
        ``"fallback"``: from a start with σ0 at or above this a singular system is
        retried damped instead of raised.
    first : int
        ``"fallback"``: the first iteration that solves the full system (a singular one
        there is a real defect at a good start).
    """

    kind: str = "none"
    lambda0: float = 1e-3
    poor_start_sigma0: float = np.inf
    first: int = 1

    def __post_init__(self) -> None:
        if self.kind not in DAMPING_KINDS:
            raise InputError(
                f"expected damping one of {', '.join(DAMPING_KINDS)}, got {self.kind!r}"
            )


def _iterations(n: int) -> str:
    """``"1 iteration"``, ``"n iterations"``."""
    return f"{n} iteration" if n == 1 else f"{n} iterations"


@dataclass
class StopRule:
    """When the loop stops: a custom rule, a per-step test or max correction < tol.

    Attributes
    ----------
    tol : float
        Stop when ``Step.max_correction`` < tol (in σ).
    ftol : float
        Also stop when an accepted step decreased vᵀPv by less than ftol times its value
        (relative decrease, Ceres's function tolerance; 0 = not used). Suits weakly
        determined parameters (points far along nearly parallel rays) whose corrections
        stay large in their σ while the fit no longer changes.
    custom : callable, optional
        ``custom(previous, current) -> bool`` on the :class:`Iteration` records.
    step_test : callable, optional
        ``step_test(step) -> bool`` (e.g. absolute thresholds per parameter).
    step_reason : str
        Reason for ``step_test`` (``{it}`` = the iteration, ``{iterations}`` = "1 iteration", "n iterations").
    may_stop : callable, optional
        ``may_stop(iteration) -> bool``: whether a stop is allowed after this
        iteration (e.g. not while parameters are held).
    """

    tol: float = 1e-6
    ftol: float = 0.0
    custom: Callable[[Iteration, Iteration], bool] | None = None
    step_test: Callable[[Step], bool] | None = None
    step_reason: str = "all corrections below xtol after {iterations}"
    may_stop: Callable[[int], bool] | None = None

    def met(self, history: list[Iteration], step: Step, it: int) -> str | None:
        """The reason to stop after iteration ``it``, or None."""
        if self.may_stop is not None and not self.may_stop(it):
            return None
        if self.custom is not None:
            if self.custom(history[-2], history[-1]):
                return f"the custom stopping rule was met after {_iterations(it)}"
            return None
        if self.step_test is not None:
            return self.step_reason.format(it=it, iterations=_iterations(it)) if self.step_test(step) else None
        if step.max_correction < self.tol:
            return f"corrections below {self.tol:g} σ after {_iterations(it)}"
        if self.ftol > 0 and len(history) >= 2:
            before, after = history[-2].cost, history[-1].cost
            if before - after <= self.ftol * before:
                return f"vᵀPv decreased by less than {self.ftol:g} of its value in iteration {it}"
        return None


@dataclass
class Run:
    """What the loop returns: the last accepted iterate and how it got there.

    Attributes
    ----------
    state : object
        The last accepted iterate.
    evaluation : Evaluation
        The evaluation at ``state``.
    history : list of Iteration
        Index 0 the start, then one record per accepted step.
    converged : bool
    reason : str
    damped_start : bool
        ``"fallback"``: a singular system was retried damped in the first iteration(s).
    """

    state: Any
    evaluation: Evaluation
    history: list[Iteration] = field(default_factory=list)
    converged: bool = False
    reason: str = ""
    damped_start: bool = False


def iterate(
    problem: IterativeProblem,
    state: Any,
    *,
    redundancy: int,
    damping: Damping = Damping(),
    stop: StopRule | None = None,
    max_iter: int = 50,
    jacobian_after: Callable[[int, Run], bool] | None = None,
    callback: Callable[[Iteration], object] | None = None,
    on_accept: Callable[[int, Step, float, Evaluation], None] | None = None,
    on_iteration: Callable[[int], None] | None = None,
) -> Run:
    """Iterate ``problem`` from ``state`` until the stop rule is met (see module docstring).

    Parameters
    ----------
    problem : IterativeProblem
    state : object
        The start (approximate values).
    redundancy : int
        n − u, for σ̂0 = √(vᵀPv / r) in the history.
    damping : Damping
    stop : StopRule, optional
        Default: max correction < 1e-6 σ.
    max_iter : int
        Maximum number of steps.
    jacobian_after : callable, optional
        ``jacobian_after(iteration, run) -> bool``: whether a trial point of that
        iteration is evaluated with derivatives (default always; False saves the last
        one's).
    callback : callable, optional
        Called with each new :class:`Iteration` (the per-step hook).
    on_accept : callable, optional
        ``on_accept(iteration, step, lam, previous_evaluation)`` after a step is
        accepted (problem-side bookkeeping: caches of the linearisation).
    on_iteration : callable, optional
        ``on_iteration(iteration)`` before each iteration's first solve.

    Returns
    -------
    Run
    """

    def s0(c: float) -> float:
        return float(np.sqrt(c / redundancy)) if redundancy > 0 else float("nan")

    stop = stop if stop is not None else StopRule()
    run = Run(
        state, problem.evaluate(state, True), reason=f"reached the maximum of {max_iter} iterations"
    )
    cost0 = run.evaluation.cost
    history = run.history
    history.append(Iteration(0, problem.snapshot(state), None, s0(cost0), cost0))
    kind = damping.kind
    lam = damping.lambda0 if kind in ("lm", "trust") else 0.0
    for it in range(1, max_iter + 1):
        if on_iteration is not None:
            on_iteration(it)
        outcome = _one_step(problem, run, it, lam, damping, jacobian_after)
        if outcome is None:  # the run ended (reason set)
            break
        step, new, ev_new, lam_used, lam_next = outcome
        if not ev_new.finite:
            run.reason = f"the observation equations became undefined (NaN/inf) in iteration {it}"
            break
        ev_old = run.evaluation
        run.state, run.evaluation = new, ev_new
        rec_lam = lam_next if kind in ("lm", "trust") else lam_used
        rec = Iteration(
            it, problem.snapshot(new), step.dx, s0(ev_new.cost), ev_new.cost, rec_lam,
            float(step.max_correction),
        )  # fmt: skip
        history.append(rec)
        if on_accept is not None:
            on_accept(it, step, lam_used, ev_old)
        # release the previous linearisation before the next one is formed (memory)
        del ev_old, outcome
        if callback is not None:
            callback(rec)
        lam = lam_next
        reason = stop.met(history, step, it)
        if reason is not None:
            run.converged, run.reason = True, reason
            break
    return run


def _one_step(problem, run: Run, it: int, lam: float, damping: Damping, jacobian_after):
    """Solve, apply and accept one step; (step, state, evaluation, λ used, next λ) or None."""
    kind = damping.kind
    state, ev = run.state, run.evaluation
    nu = None  # "trust": the growth factor of λ after a rejected step
    while True:
        try:
            step = problem.solve(state, ev, lam, it)
        except NotDeterminableError as exc:
            if kind == "trust" and it > 1 and lam * 2.0 * (nu or 1.0) <= 1.0 / TRUST_MIN_LAMBDA:
                # solvable in iteration 1, singular now: a numerical loss of definiteness
                # (weak parameters, down-weighted rays) — as Ceres, a failed solve is a
                # rejected step: retried with more damping
                nu = 2.0 if nu is None else 2.0 * nu
                lam = max(lam * nu, damping.lambda0)
                continue
            if kind != "fallback":
                if it == 1:
                    raise
                run.reason = (
                    f"diverged: the normal matrix became singular in iteration {it} ({exc})"
                )
                return None
            # at a good start a singular system is a real defect; at a poor start (σ0 ≫
            # 1) it may be an artefact of the approximations: damped steps are tried and
            # the caller verifies the undamped system at the solution
            if (
                it == damping.first
                and lam == 0
                and run.history[-1].sigma0 < damping.poor_start_sigma0
            ):
                raise
            run.damped_start = run.damped_start or it <= damping.first
            lam = max(10 * lam, 1e-3)
            if lam > 1e8:
                run.reason = f"the normal equations stayed singular in iteration {it}"
                return None
            continue
        new = problem.apply(state, step)
        jac = jacobian_after(it, run) if jacobian_after is not None else True
        ev_new = problem.evaluate(new, jac)
        c_new = ev_new.cost
        if kind == "none":
            return step, new, ev_new, lam, lam
        if kind == "lm":
            if (np.isfinite(c_new) and c_new <= ev.cost) or lam > 1e10:
                return step, new, ev_new, lam, max(lam / 10.0, 1e-12)
            lam *= 10.0
            continue
        if kind == "trust":
            if np.isfinite(c_new) and c_new <= ev.cost:
                return step, new, ev_new, lam, max(lam / 3.0, TRUST_MIN_LAMBDA)
            nu = 2.0 if nu is None else 2.0 * nu
            lam *= nu
            if lam > 1.0 / TRUST_MIN_LAMBDA:
                run.reason = f"no step decreases vᵀPv in iteration {it} (damping exhausted)"
                return None
            continue
        if np.isfinite(c_new) and c_new <= ev.cost * (1 + 1e-12) + 1e-12:
            return step, new, ev_new, lam, (lam / 10 if lam > 1e-6 else 0.0)
        lam = max(10 * lam, 1e-4)
        if lam > 1e8:
            run.reason = f"no step decreases vᵀPv in iteration {it} (damping exhausted)"
            return None
