"""The bundle problem as the engine's loop sees it: evaluate, solve, apply, accept.

:class:`BundleSteps` implements the steps of :func:`orientviz.adjust.loop.iterate` for a
:class:`~orientviz.bundle.problem.BundleProblem`: the weighted misclosures and Jacobians
at an iterate, the step from the point-reduced normal equations, and what the iterations
hand on. Its knobs are fields of the problem's
:class:`~orientviz.bundle.BundleOptions`:

* a robust loss (``options.loss``, :mod:`._loss`): Σρ is the cost, each step's rays are
  weighted by √ρ′ of the iterate (set in the problem's ray weights before its normal
  equations are formed); least-squares steps come first for Huber and soft-L1, and for
  Cauchy from a start with σ0 ≥ :data:`LOSS_SIGMA0`; in the run's tail the steps are
  over-relaxed (:data:`ROBUST_OVERRELAX`; by the model's curvature ratio along an
  established linear tail, :data:`OVERRELAX_MIN_RATIO`) and a convex loss's model takes the
  curvature along down-weighted rays' misclosures closer to the true one
  (:data:`ROBUST_TAIL_FLOOR`);
  an over-relaxed step the loop rejects is retried as the model's own step (ω = 1, kept
  from its solve: no new solve, whatever λ the loop asks), and a step rejected again is
  solved at the loop's λ without the over-relaxation and the tail's model; in every
  robust step of a convex loss the points with a ray beyond the scale get their own
  Newton correction given the images' one, and each point keeps the correction (the
  joint step's or a Newton one) that lowers the Σρ of its rays most (:mod:`._tail`) —
  in a small block left out after a search that adds little to its step's decrease
  (:data:`SEARCH_GAIN`) until the run's tail (:data:`ROBUST_TAIL`), there until two
  searches in a row each gain less than the run's ftol;
* a point the step held along its depth (its block V numerically singular,
  :func:`~orientviz.bundle.reduced.inv3_held`) has its depth sought alone after the step,
  given the step's new image parameters (:mod:`._depth`);
* the additional parameters are held at their values in the first step from a poor
  start; their border E, F is reused in the next iteration when the last step moved
  nothing by more than ``ap_reuse`` (the Jacobians then change by about as little, less
  than the tolerance of the border's solve) — until a step meets the stopping rule
  (see below), and not in a robust run once the loss is on (the rays' weights change
  with the iterate: a border of the last weights gave steps the loop rejected until
  damped, and runs that did not converge);
* ``options.ftol`` does not stop a least-squares run on a poor step: one whose decrease
  of vᵀPv meets it but is less than ¼ of the decrease its linear model predicted, that
  prediction above ftol (:mod:`._gain`; a point whose rays diverge, receding along them);
* from a poor start (σ0 ≥ ``local_sigma0``, last correction ≥ ``local_min_correction``)
  steps rotate the image frames (:mod:`orientviz.bundle.model._local_rotation`);
* *chord* steps: a plain bundle without precision solves the step after a small one
  (move < ``chord_reuse``) with the normal matrix of that step, dx = N(x_old)⁻¹ Jᵀ P (l − f)
  at the new iterate — only the gradient is formed anew, N's point blocks and the factor
  of S are the old ones. Chord steps follow each other while each corrects by less than
  ``chord_contraction`` times the step before; one that does not is dropped and the step
  solved in full at the same iterate. A factor of a step in frame rotations serves steps
  in ω, φ, κ through the map A of :func:`~orientviz.bundle.model.angle_map`
  (J_θ = J_δ·A per image).

Why a step on a reused border may not stop the run: it solves with E, F of an earlier
iterate, δ̃ = Ñ⁻¹ g, and where the border's Schur complement Fs = F − Eᵀ S⁻¹ E is nearly
singular (free parameters per strip) a relative change of E, F far below ``ap_reuse``
changes Fs by much more: ‖Ñ⁻¹ N − I‖ need not be small, and a small δ̃ does not bound the
distance to the optimum. Such a step may meet the tolerance but not stop the run; from
then on the border is formed at every iterate, and the run stops on a step solved on the
border of its own iterate. That step is inexact only by the conjugate gradients'
tolerance (``pcg_tol``, relative to the step): it reads the distance to the optimum
within that factor, as an exact Newton step does.

Why the stopping rule may judge a chord step: at one iterate the chord correction
δ_c = N_old⁻¹ g and the Newton correction δ_N = N⁻¹ g satisfy δ_N = N⁻¹ N_old δ_c, so with
‖N⁻¹ N_old − I‖ ≤ ε (in the rule's norm, corrections in conditional σ) the rule reads δ_c
within a factor 1 ± ε of δ_N. Near the optimum chord steps shrink the error by about ε
each; the ratio θ of successive corrections observes that, and as long as it holds the
iterate after a correction δ_k is within θ/(1 − θ)·‖δ_k‖ of the optimum — with θ < 1/2
within ‖δ_k‖ < tol, the distance a Newton stop leaves or less. ε grows faster than the
move (the blocks' weak bending modes change most), hence the small ``chord_reuse``
(measurements: ``benchmarks/README.md``, "Chord steps").
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...adjust.loop import Evaluation, Step
from ..model import angle_map
from ..problem import BundleProblem, BundleState
from ._depth import depth_search
from ._gain import POOR_GAIN, predicted_decrease
from ._loss import RobustLoss
from ._tail import point_newton, point_search, tail_model

F64 = NDArray[np.float64]
#: A redescending loss (Cauchy) is on from the start when the start's σ0 (of least
#: squares) is below this: the misclosures of most rays are then a few σ (Ladybug with
#: 2 % gross errors starts at 8; there the least-squares optimum, pulled by the gross
#: errors, lies in a worse basin: ½Σρ 6 089 against 6 076 from the start). From a poorer
#: start (a strip from approximations: σ0 1 500, then 28 after one step) least-squares
#: steps come first — Cauchy there down-weighted the wrong rays — until σ0 falls below
#: this. The convex losses (Huber, soft-L1) always start from least-squares steps …
LOSS_SIGMA0: float = 10.0
#: … and a redescending loss is switched on at the latest after a least-squares step that
#: lowers vᵀPv by at most this fraction of its value, or corrects by less than 1 σ …
LOSS_SWITCH: float = 1e-2
#: … a convex loss after a least-squares step that lowers vᵀPv by at most this fraction
#: (or corrects by less than 1 σ): one least-squares step takes the start's largest
#: misclosures out before the loss weighs them, and more such steps let the gross errors
#: pull the solution into a worse basin (benchmarks/README.md, robust losses on Ladybug).
#: A decrease between :data:`LOSS_SWITCH` and this fraction counts only after a step that
#: lowered vᵀPv by more: a damped first step that barely moves has not taken them out. A
#: step that lowered vᵀPv by more than this fraction switches the loss on too when its
#: linear model predicted that decrease to within :data:`LOSS_SWITCH` of the new vᵀPv
#: (:meth:`BundleSteps._modelled_warm_up`: the next least-squares step would be a settled
#: one; DBAT sxb 2 warm-up steps → 1, Ladybug's damped steps miss it by 8 % and more).
LOSS_SWITCH_CONVEX: float = 0.3
#: In a robust run's tail — the last step lowered Σρ by less than :data:`ROBUST_TAIL` of its
#: value — the step is taken :data:`ROBUST_OVERRELAX` times (over-relaxed reweighting). The
#: √ρ′-scaled model overestimates the curvature along the misclosures of down-weighted rays
#: (for Huber beyond its scale the true value is 0), so near the optimum its steps fall short
#: by a factor that changes little from step to step: Σρ then falls linearly, each decrease
#: ~5 % below the last (Ladybug with 2 % gross errors). A step ω·δ shrinks such an error by
#: 1 − ωμ instead of 1 − μ (μ the model's share of the true step); ω = 1.5 keeps a component
#: the model gets right (μ = 1) converging (|1 − ω| = 0.5; ω = 2 can stall it), and a step
#: that raises Σρ is rejected; its retry is the model's own step δ (see the module
#: docstring), then damped as any. The fixed point is the same (δ = 0 there). Steps and
#: optima with and without it: benchmarks/README.md, robust losses on Ladybug.
ROBUST_TAIL: float = 1e-3
ROBUST_OVERRELAX: float = 1.5
#: A convex loss's tail step is taken ω times where the model's curvature along the last two
#: accepted tail steps exceeded the true one by more than :data:`OVERRELAX_MIN_RATIO` both
#: times, the two ratios agreeing to within :data:`OVERRELAX_AGREE` (:meth:`BundleSteps.
#: _curvature_ratio`: a linear tail along one mode the model holds far too stiff — Ladybug's
#: Huber tail, a point and the cameras moving together, ratios ~300, 0.984 per step): ω is
#: the smaller ratio, at most :data:`OVERRELAX_MAX`. Along such a mode the optimum lies that
#: many model steps away; a step that raises Σρ is retried as the model's own (as any
#: over-relaxed one). DBAT's tails (ratios 2–7) keep ω = 1.5. Measurements:
#: benchmarks/README.md, the loop's over-relaxation by the curvature ratio.
OVERRELAX_MIN_RATIO: float = 10.0
OVERRELAX_AGREE: float = 0.25
OVERRELAX_MAX: float = 64.0
#: In the tail a convex loss's model also takes the curvature along each beyond-scale ray's
#: misclosure closer to the true one: ρ′ + 2sρ″ (0 for Huber, ρ′/(1 + s/b) for soft-L1),
#: floored at this fraction of ρ′ (a 2 × 2 per-ray model, Triggs et al. 2000: rows P½J
#: of the ray turned into (I − (1 − √c) r̂r̂ᵀ) P½J, its misclosure divided by √c, with
#: c the floored ratio: the gradient unchanged, the curvature along r̂ c·ρ′ instead of ρ′).
#: Only in the tail: from a poorer iterate its steps go wrong. For every camera set (a
#: linear set's weighted design is turned for the solve and restored after it, as a
#: camera model's), not for a redescending loss. Steps and optima with other floors, and
#: of linear sets with and without it: benchmarks/README.md.
ROBUST_TAIL_FLOOR: float = 0.3
#: The points' own search (:mod:`._tail`) is left out until the run's tail (a step that
#: lowers Σρ by less than :data:`ROBUST_TAIL`) after an accepted step whose search lowered
#: Σρ by less than this fraction of the step's decrease, in a block of at most
#: :data:`SEARCH_GATE_RAYS` rays; in the tail it runs in every step (the slow linear tail
#: is what it removes: small simulated aerial blocks with gross errors crawled 50–120 steps
#: or stopped 1e-4 above their optimum when it stayed out there) until two tail searches
#: in a row each lower Σρ by less than the run's ftol·Σρ (it can no longer move where the
#: run stops: then it is left out for the rest of the run; one such search alone may come
#: before the tail model's steps move points again). Outside the tail its fixed cost
#: (some hundred array operations: the points' 3 × 3 systems, one evaluation of their
#: rays at two corrections) weighs as much as a step, and such shares do not come with
#: fewer steps (DBAT camcal: 0.03–2.7 % in every step). In larger blocks it costs a few
#: per cent of a step and is kept: a small share there may precede large ones (BAL 21
#: soft-L1: 0.9 %, then 16–40 % per step). Shares per step: benchmarks/README.md.
SEARCH_GAIN: float = 0.02
SEARCH_GATE_RAYS: int = 10_000
#: No ftol stop after a least-squares step damped by a λ of at least this that does not
#: meet the tolerance (the damping then at least equals the curvature on the normal
#: matrix's diagonal, the step is shortened by half or more): its small decrease of vᵀPv
#: is the damping's. From a misplaced image (σ0 1e4) "trust" reached λ 1e6 in its 4th
#: step and stopped there on ftol at σ0 8 473, "converged". A step below the tolerance may
#: still stop the run (at an optimum reached to rounding, undamped steps are rejected by
#: the rounding of vᵀPv and λ grows while the corrections vanish).
STOP_MAX_LAMBDA: float = 1.0


class _Linearisation(tuple):
    """(rw, Je, Jp) of an evaluation; ``local``: Je by rotations of the image frames;
    ``scale``: √ρ′ per ray of a robust loss (None: least squares) — rw and the weights
    of Je, Jp are scaled by it; ``terms``: (s, ρ′) per ray with it (s the squared
    1/σ-weighted misclosure); ``deferred``: the derivatives were asked for but not yet
    formed (Je = Jp = None; :meth:`BundleSteps.resolve` forms them, by ``local``)."""

    def __new__(
        cls,
        data: tuple,
        local: bool = False,
        scale: F64 | None = None,
        deferred: bool = False,
        terms: tuple[F64, F64] | None = None,
    ):
        out = super().__new__(cls, data)
        out.local = local
        out.scale = scale
        out.deferred = deferred
        out.terms = terms
        return out


class BundleSteps:
    """The bundle problem as the engine's loop sees it (its :class:`orientviz.adjust.Step` objects).

    Evaluates the weighted misclosures and Jacobians at a :class:`BundleState`, forms the
    point-reduced normal equations and solves them (:meth:`BundleProblem.normal`,
    :meth:`BundleProblem.solve`), and keeps per run what the iterations hand on: the
    hold of the additional parameters in the first step, the reuse of their border, and
    the last undamped linearisation (the precision may reuse it).
    """

    def __init__(
        self,
        prob: BundleProblem,
        red_names: list[str],
        keep_x: bool,
        precision: bool,
        loss: RobustLoss | None = None,
    ):
        self.prob, self.red_names = prob, red_names
        # a robust loss (._loss): the rays' weights are the problem's 1/σ times √ρ′ of the
        # evaluation whose normal equations are formed (set in place before each)
        self.loss = loss
        self.base_weight = prob.obs.weight.copy() if loss is not None else None
        # the loss is on from a start with σ0 below LOSS_SIGMA0; from poorer
        # approximations (every ray an outlier: a redescending loss would down-weight the
        # wrong ones) least-squares steps come first, until σ0 falls below it or the steps
        # settle (see accepted); the loop's current evaluation is then made robust
        self.loss_on = False
        self.switch_pending = False
        self._ls_dropped = False  # a least-squares step lowered vᵀPv by > LOSS_SWITCH_CONVEX
        self.keep_x, self.precision = keep_x, precision
        # a camera model's trial points are evaluated without derivatives (:meth:`evaluate`):
        # its Jacobians and design cost ~5× its projection, and a rejected step needs none
        self.defer = prob.ap.lens is not None
        self.hold_first = False
        self.lin = None  # (normal equations, factor, Jacobians) of the last plain step
        self._start: tuple | None = None
        # rotation steps in the image frames while the start is poor (._local_rotation)
        self.local_allowed = prob.local_rotations_allowed
        self.local_step = False  # the last accepted step rotated the image frames
        self.last_cost: float | None = None  # vᵀPv of the last accepted state
        self.pending_cost: float | None = None  # … of the last evaluated one
        self.last_correction = np.inf
        # chord steps (options.chord_reuse): the factor of the last full step while it may serve
        self.chord_allowed = not precision and not (prob.q or prob.aux or prob.ap.lens is not None)
        self.chord_factor = None  # (factor of S, its NormalEquations, local?)
        self.chord_pending = None  # the factor of the last solved step, if it may serve
        self.chord_step = False  # the last solved step used chord_factor
        # the scale of the step's move (_relative_move): the border's median ray length
        # with additional parameters, else the median ray of the first iterate that asks
        self.ray_length: float | None = prob.ap.ray_length if prob.q else None
        self.last_rel, self.last_local = np.inf, False  # of the last solved step
        # the last solved step used a reused border E, F (it may not stop the run), and
        # whether a step has met the tolerance (the border is then formed anew at every
        # iterate: the run ends on a step solved on its own iterate's border)
        self.last_reused = False
        self.border_fresh = False
        self.robust_tail = False  # the last robust step lowered Σρ by < ROBUST_TAIL
        # the state of the last solve: a solve at the same state again is a retry of a
        # rejected step (the tail's over-relaxation and model are then left out)
        self._solved_at: BundleState | None = None
        self._unrelaxed: Step | None = None  # the model's own step of an over-relaxed one
        self._sigma = None  # diagonals (U, V, F) of the last solve (the stopping measure)
        self.points_moved = 0  # points the last search moved otherwise than the joint step
        self._ratios = (0.0, 0.0)  # _curvature_ratio of the last two accepted steps
        self._held = None  # the point unknowns the last solved step held (._depth)
        self.depths_moved = 0  # held points whose depth the last step's search moved
        self.search_gain = None  # … and the decrease of Σρ it added (None: no search)
        self.search_off = False  # the searches stopped paying (SEARCH_GAIN)
        self.stop_ftol = 0.0  # the run's ftol (set by the caller; a robust run's own)
        self._tail_search = False  # the next step searches because the run is in its tail
        self._search_spent = False  # two tail searches in a row gained < stop_ftol·Σρ each
        self._search_low = False  # … and whether the last one did
        self._drops = (0.0, 0.0)  # the decreases of Σρ of the last two robust steps
        # the start of the last solved step and its additional parameters' design (the
        # step's predicted decrease, ._gain), and whether the last accepted least-squares
        # step was a poor one whose decrease met ftol (it may not stop the run)
        self._gain_from: tuple | None = None
        self.poor_step = False
        self.damped_step = False  # the last accepted step was damped by λ ≥ STOP_MAX_LAMBDA

    def start(self, st: BundleState) -> Evaluation:
        """Evaluate the start once (the loop asks for it again: no second evaluation)."""
        if self.local_allowed:  # σ0 of the start decides how its Jacobian is formed
            self.last_cost = self._evaluate(st, False, False, keep=True).cost
            # a poor start: derivatives by rotations of the image frames (from the kept
            # projection: the rays are projected once)
            ev = self._evaluate(st, True, self._poor())
        else:
            ev = self._evaluate(st, True, False)
        if self.loss is not None and self.loss.redescending and not self._poor_sigma0(ev.cost):
            # a redescending loss from a good start: ρ at once (see LOSS_SIGMA0)
            self.loss_on = True
            ev = self._evaluate(st, True, self.is_local(ev))
        self._start = (st, ev)
        return ev

    def _poor_sigma0(self, cost: float) -> bool:
        """σ0 of vᵀPv ``cost`` at least :data:`LOSS_SIGMA0` (too poor for a robust loss)."""
        dof = self.prob.redundancy
        return dof > 0 and float(np.sqrt(cost / dof)) >= LOSS_SIGMA0

    def evaluate(self, st: BundleState, jacobian: bool) -> Evaluation:
        """The cost at ``st`` and, with ``jacobian``, its linearisation — for a camera
        model (:attr:`defer`) only the cost: the derivatives are formed when a step is
        solved from ``st`` (:meth:`resolve`), never for a trial point that is rejected."""
        if self._start is not None and self._start[0] is st:
            ev, self._start = self._start[1], None
            return ev
        local = jacobian and self.local_allowed and self._poor()
        if jacobian and self.defer:
            ev = self._evaluate(st, False, local)
            ev.data = _Linearisation(ev.data, local, deferred=True)
            ev.data.robust = self.loss_on  # its misclosures: weighted by 1/σ only
            return ev
        # a robust trial point without derivatives (its step expected to stop the run,
        # :meth:`expects_stop`): the projection is kept for the run's end or the
        # derivatives if the run goes on (the next evaluation at another point drops it)
        return self._evaluate(st, jacobian, local, keep=not jacobian and self.loss_on)

    def resolve(self, st: BundleState, ev: Evaluation) -> None:
        """Give ``ev`` (at ``st``, evaluated without derivatives) its linearisation, in
        place: by the frame rotations decided when it was evaluated (a deferred one) or
        as a new evaluation would (one evaluated where a stop was expected)."""
        data = ev.data
        deferred = getattr(data, "deferred", False)
        local = data.local if deferred else self.local_allowed and self._poor()
        known = data[0] if deferred and getattr(data, "robust", False) and self.loss_on else None
        full = self._evaluate(st, True, local, rw_base=known)
        ev.cost, ev.finite, ev.data = full.cost, full.finite, full.data

    def _evaluate(
        self,
        st: BundleState,
        jacobian: bool,
        local: bool,
        keep: bool = False,
        rw_base: F64 | None = None,
    ) -> Evaluation:
        """The evaluation at ``st``; ``rw_base``: its misclosures weighted by 1/σ, known
        from an evaluation without derivatives at ``st`` (a robust loss's weights are then
        set before a camera model's design is formed)."""
        if self.loss_on:
            return self._evaluate_robust(st, jacobian, local, keep, rw_base)
        rw, Je, Jp = self.prob.residuals(st, jac=jacobian, local=local, keep=keep)
        cost = self.prob.cost(st, rw)
        self.pending_cost = cost
        return Evaluation(cost, bool(np.isfinite(cost)), _Linearisation((rw, Je, Jp), local))

    def _evaluate_robust(
        self,
        st: BundleState,
        jacobian: bool,
        local: bool,
        keep: bool,
        rw_base: F64 | None = None,
    ):
        """Σ ρ(s) + the pseudo-observations' vᵀPv at ``st``; with ``jacobian`` the rays
        weighted by 1/σ·√ρ′(s) (the Gauss-Newton model of ρ, see :mod:`._loss`): the
        misclosures first with 1/σ, then the weights scaled (the normal equations weight
        the Jacobians by them; a camera model's design is re-weighted). ``rw_base``: the
        misclosures with 1/σ at ``st``, known (see :meth:`_evaluate`)."""
        prob, weight = self.prob, self.prob.obs.weight
        weight[...] = self.base_weight
        lens = jacobian and prob.ap.lens is not None
        if lens and rw_base is not None:  # the weights first: the design is formed once
            s = np.einsum("ij,ij->i", rw_base, rw_base)
            rho, rho1 = self.loss(s)
            cost = float(np.sum(rho)) + prob.cost(st, rw_base[:0])
            if np.isfinite(cost):
                self.pending_cost = cost
                scale = np.sqrt(rho1)
                weight *= scale[:, None]
                _, Je, Jp = prob.residuals(st, jac=True)  # (Je, Jp: unweighted)
                rw = rw_base * scale[:, None]  # as the path below forms it
                lin = _Linearisation((rw, Je, Jp), local, scale, terms=(s, rho1))
                return Evaluation(cost, True, lin)
            weight[...] = self.base_weight
        # a camera model is evaluated once, with its derivatives (its design is then
        # re-weighted); a pinhole's projection is kept for the Jacobians' pass
        rw, Je, Jp = prob.residuals(st, jac=lens, keep=(jacobian or keep) and not lens)
        s = np.einsum("ij,ij->i", rw, rw)
        rho, rho1 = self.loss(s)
        cost = float(np.sum(rho)) + prob.cost(st, rw[:0])  # the rays by ρ, the rest by vᵀPv
        self.pending_cost = cost
        scale = None
        if jacobian and np.isfinite(cost):
            scale = np.sqrt(rho1)
            weight *= scale[:, None]
            if lens:
                rw = rw * scale[:, None]
                if prob.q:
                    prob.run.ap = prob.ap.with_design(prob.ap.A, weight)
            else:
                rw, Je, Jp = prob.residuals(st, jac=True, local=local)
        lin = _Linearisation((rw, Je, Jp), local, scale, terms=None if scale is None else (s, rho1))
        return Evaluation(cost, bool(np.isfinite(cost)), lin)

    def _switch_evaluation(self, st: BundleState, ev: Evaluation) -> Evaluation:
        """The robust evaluation at ``st`` where the loss is switched on, ``ev`` the least-
        squares one there: a pinhole's Jacobians (unweighted) are ``ev``'s, its misclosures
        are weighted anew; a camera model's deferred misclosures (1/σ) are ``ev``'s (the
        values :meth:`_evaluate` forms)."""
        prob = self.prob
        rw, Je, Jp = ev.data
        local = self.is_local(ev)
        if prob.ap.lens is not None and getattr(ev.data, "deferred", False):
            # a camera model's deferred evaluation: its misclosures (1/σ) are known, the
            # design is formed once, with the robust weights (:meth:`_evaluate_robust`)
            return self._evaluate(st, True, local, rw_base=rw)
        if Je is None or prob.ap.lens is not None:
            return self._evaluate(st, True, local)
        weight = prob.obs.weight
        weight[...] = self.base_weight
        s = np.einsum("ij,ij->i", rw, rw)  # rw: weighted by 1/σ (least squares)
        rho, rho1 = self.loss(s)
        cost = float(np.sum(rho)) + prob.cost(st, rw[:0])
        self.pending_cost = cost
        if not np.isfinite(cost):
            return Evaluation(cost, False, _Linearisation((rw, None, None), local))
        scale = np.sqrt(rho1)
        weight *= scale[:, None]
        rw = prob.reweighted(st)  # (from the least-squares evaluation's projection)
        return Evaluation(cost, True, _Linearisation((rw, Je, Jp), local, scale, terms=(s, rho1)))

    def _tail_model(self, rw: F64, Je: F64, Jp: F64, scale: F64 | None):
        """In a convex loss's tail (:data:`ROBUST_TAIL_FLOOR`): the rays beyond the scale
        with their curvature along the misclosure c·ρ′ (c = max((ρ′ + 2sρ″)/ρ′, floor))
        — rows (I − (1 − √c) r̂r̂ᵀ) P½J (Je, Jp, the additional parameters' design) and misclosure
        P½r/√c. ``rw``: P½r with the weights 1/σ·√ρ′ (``scale`` = √ρ′ per ray), ``Je``,
        ``Jp`` unweighted (the normal equations weight them). Returns (rw, Je, Jp, design
        to restore after the solve or None); unchanged outside the tail."""
        prob, loss = self.prob, self.loss
        if not self.robust_tail or self._retry or scale is None or loss.redescending:
            return rw, Je, Jp, None
        return tail_model(prob, loss, rw, Je, Jp, scale, ROBUST_TAIL_FLOOR)

    def weigh(self, ev: Evaluation) -> None:
        """Set the rays' weights to those of ``ev``'s linearisation (a robust loss; the
        normal equations, the precision and a camera model's design read them)."""
        scale = getattr(ev.data, "scale", None)
        if self.loss is None or scale is None:
            return
        np.multiply(self.base_weight, scale[:, None], out=self.prob.obs.weight)
        self.reweigh_design()

    def reweigh_design(self) -> None:
        """A linear additional-parameter set: its weighted design with the rays' current
        weights (a camera model's design is weighted as it is formed)."""
        prob = self.prob
        if prob.q and prob.ap.lens is None:
            prob.run.ap = prob.ap.with_design(prob.ap.A, prob.obs.weight)

    def _poor(self) -> bool:
        """Still far from the solution: σ0 of the last accepted state (the start: unknown,
        poor) at least ``options.local_sigma0`` and the step to the state evaluated not small (its
        correction: the last one solved)."""
        dof = self.prob.redundancy
        if self.last_cost is None or dof <= 0:
            return self.last_cost is None
        s0 = float(np.sqrt(self.last_cost / dof))
        opts = self.prob.options
        return s0 >= opts.local_sigma0 and self.last_rel >= opts.local_min_correction

    @staticmethod
    def is_local(ev: Evaluation) -> bool:
        """Whether ``ev``'s Jacobian is by rotations of the image frames."""
        return bool(getattr(ev.data, "local", False))

    def begin(self, it: int) -> None:
        self.prob.run.border.hold = self.hold_first and it == 1
        self.lin = None  # released before the next normal equations are built

    def may_stop(self) -> bool:
        """Whether the run may stop: not before a robust loss is switched on, nor after a
        step solved on a reused border E, F (see the module docstring), nor by ftol after
        a least-squares step damped by λ ≥ :data:`STOP_MAX_LAMBDA` (its small decrease is
        the damping's, not the optimum's)."""
        if self.last_reused or self.poor_step or self.damped_step:
            return False
        return self.loss is None or (self.loss_on and not self.switch_pending)

    def expects_stop(self, ftol: float) -> bool:
        """Whether the step being taken is expected to meet ``ftol`` (a robust run's
        relative decrease of Σρ): its decrease extrapolated from the last two robust steps'
        d₁, d₂ as d₂²/d₁ (their linear convergence) below ftol·Σρ. Its trial point then
        is evaluated without derivatives (formed from the kept projection if the run goes
        on: the same values, :meth:`resolve`)."""
        d1, d2 = self._drops
        if not (self.loss_on and not self.switch_pending and ftol > 0 and d1 > 0 and d2 >= 0):
            return False
        return d2 * d2 / d1 < ftol * self.last_cost

    def stops(self, tol: float) -> bool:
        """Whether the last solved step meets the stopping rule (``tol``) once accepted:
        the state it leads to then needs no derivatives (without the precision)."""
        return self.last_rel < tol and not (
            self.prob.run.border.hold or self.last_local or self.last_reused
        )

    def solve(self, st: BundleState, ev: Evaluation, lam: float, iteration: int) -> Step:
        prob = self.prob
        self._retry = st is self._solved_at  # the loop rejected the step from st
        self._solved_at = st
        kept, self._unrelaxed = self._unrelaxed, None
        if self._retry and kept is not None:  # a rejected over-relaxed step: ω = 1 first
            self.last_rel, self.last_reused, self.chord_pending = kept.max_correction, False, None
            dc, dp, da = kept.data[:3]
            kept.data = kept.data[:6] + (self._point_newton(st, ev, dc, dp, da, lam),)
            return kept
        switched = self.switch_pending
        if switched:  # the loss is switched on: the loop's evaluation at st too
            self.switch_pending = False
            robust = self._switch_evaluation(st, ev)
            ev.cost, ev.finite, ev.data = robust.cost, robust.finite, robust.data
            self.last_cost = robust.cost
        if ev.data[1] is None:  # evaluated without derivatives (deferred, or a stop was expected)
            self.resolve(st, ev)
        rw, Je, Jp = ev.data
        local = self.is_local(ev)
        self.weigh(ev)
        rw, Je, Jp, design = self._tail_model(rw, Je, Jp, getattr(ev.data, "scale", None))
        chord = None  # a chord step in ω, φ, κ, or in frame rotations by such a factor
        # (not where the loss was just switched on: the factor is of the unweighted rays)
        if (
            self.chord_factor is not None
            and lam == 0
            and not switched
            and (self.chord_factor[2] or not local)
        ):
            chord = self._chord(st, rw, Je, Jp, local)  # None: it would not contract enough
        self.chord_step = chord is not None
        try:
            if chord is None:
                ne = prob.normal(st, rw, Je, Jp, lam, hold=True)
                dc, dp, da, fac = prob.solve(ne, self.red_names)
                rel = self._correction(ne, dc, dp, da)
            else:
                rel, ne, dc, dp, da, fac = chord
        finally:
            if design is not None:  # the parameters' own design again (a retry, the end)
                prob.run.ap = design.with_design(design.A, prob.obs.weight)
        self._sigma = (ne.diagU, ne.diagV, ne.diagF if prob.q or prob.na else None)
        self._held = None if ne.held is None else ne.held.points
        if self.robust_tail and not self._retry and self.loss_on and not self.switch_pending:
            w = self._overrelaxation()
            self._unrelaxed = Step(rel, self._dx(dc, dp, da), (dc, dp, da, None, None, local, None))
            dc, dp, da = dc * w, dp * w, da * w
            rel *= w
        points = self._point_newton(st, ev, dc, dp, da, lam)
        dx = self._dx(dc, dp, da) if points is None else None  # (the search's: in apply)
        self.last_rel, self.last_local = rel, local
        self.last_reused = chord is None and bool(getattr(ne.ap, "reused", False))
        self.chord_pending = None
        if self.chord_allowed and lam == 0:
            if self.chord_step:  # the factor served: it may serve the next step too
                self.chord_pending = self.chord_factor
            elif self._relative_move(st, dc, dp) < prob.options.chord_reuse:
                self.chord_pending = (fac, ne, local)
        # the normal equations and their factor live on only where the precision may reuse
        # them (an undamped plain step, see accepted); else they are freed before the trial
        # point's Jacobians are formed (the peak memory of a large block)
        if not (self.precision and lam == 0 and not (prob.q or prob.aux or local)):
            ne = fac = None
        self._gain_from = (st, prob.run.ap if prob.q else None)  # (its A_csr: read if needed)
        return Step(rel, dx, (dc, dp, da, fac, ne, local, points))

    def _overrelaxation(self) -> float:
        """ω of a tail step: :data:`ROBUST_OVERRELAX`, or the smaller curvature ratio of the
        last two accepted steps where both exceed :data:`OVERRELAX_MIN_RATIO` and agree to
        within :data:`OVERRELAX_AGREE`, at most :data:`OVERRELAX_MAX`."""
        a, b = self._ratios
        if min(a, b) > OVERRELAX_MIN_RATIO and abs(a - b) <= OVERRELAX_AGREE * b:
            return min(a, b, OVERRELAX_MAX)
        return ROBUST_OVERRELAX

    def _curvature_ratio(self, step: Step, previous: Evaluation, gain_from) -> float:
        """The reweighted model's curvature along the accepted step s over the true one.

        Along s the model is Σρ − 2α rᵀJs + α²‖Js‖² (r, J of ``previous``, weighted by
        1/σ·√ρ′), the true Σρ − 2α rᵀJs + α²c (the same slope): the realised decrease d
        at α = 1 gives c = 2 rᵀJs − d, and the ratio is ‖Js‖²/c — the multiple of s
        at which the true quadratic along it is least, over the one the model would take
        (1/ω of an over-relaxed s). inf where c ≤ 0 (the true Σρ not convex along s), 0
        where it cannot be formed (no derivatives kept, a step in frame rotations). The
        points' search makes d larger than the joint step's own: the ratio then errs high
        (a step too long is rejected and retried, see :data:`OVERRELAX_MIN_RATIO`). The
        pseudo-observations (weighted control, the additional parameters' σ, a given
        exterior orientation) are not in the model's slope and curvature here, while d
        includes their change: with such priors the ratio is not the model's (it reads
        inf or far too high, and two rarely agree)."""
        scale = getattr(previous.data, "scale", None)
        rw, Je, Jp = previous.data
        if scale is None or Je is None or gain_from is None or self.is_local(previous):
            return 0.0
        prob, obs = self.prob, self.prob.obs
        dc, dp, da = step.data[0], step.data[1], step.data[2]
        Jd = np.einsum("nij,nj->ni", Je, np.take(dc, obs.image, axis=0))
        var = obs.column >= 0
        Jd[var] += np.einsum("nij,nj->ni", Jp[var], np.take(dp, obs.column[var], axis=0))
        ap = gain_from[1]
        if ap is not None and prob.q:
            Jd += (ap.A_csr @ da[: prob.q]).reshape(-1, 2)
        Jd *= self.base_weight
        Jd *= scale[:, None]
        model = float(np.sum(Jd * Jd))
        true = 2.0 * float(np.sum(rw * Jd)) - (previous.cost - self.pending_cost)
        return model / true if true > 0 else np.inf

    def _poor_step(self, step: Step, previous: Evaluation) -> bool:
        """Whether an accepted least-squares step whose decrease of vᵀPv meets
        ``options.ftol`` realised less than :data:`._gain.POOR_GAIN` of the decrease its
        linear model predicted, that prediction itself above ftol (:mod:`._gain`): such a
        step does not show that vᵀPv has stopped falling."""
        ftol, before = self.prob.options.ftol, previous.cost
        if self.loss is not None or not ftol > 0 or self._gain_from is None:
            return False
        actual = before - self.pending_cost
        if actual > ftol * before:
            return False
        pred = self._predicted(step, previous)
        return pred > ftol * before and actual < POOR_GAIN * pred

    def _modelled_warm_up(self, step: Step, previous: Evaluation) -> bool:
        """Whether an accepted least-squares step of a convex loss's warm-up lowered vᵀPv by
        more than :data:`LOSS_SWITCH_CONVEX` and as its linear model predicted, to within
        :data:`LOSS_SWITCH` of the new vᵀPv (:mod:`._gain`): it reached the least-squares
        optimum but for the nonlinearity it did not model, and a next least-squares step
        would lower vᵀPv by about that — a settled one (the loss is switched on now, not
        after that step)."""
        if (
            self.loss is None
            or self.loss_on
            or self.loss.redescending
            or self._gain_from is None
            or not previous.cost > 0
        ):
            return False
        actual = previous.cost - self.pending_cost
        if not actual > LOSS_SWITCH_CONVEX * previous.cost:
            return False
        return abs(actual - self._predicted(step, previous)) <= LOSS_SWITCH * self.pending_cost

    def _predicted(self, step: Step, previous: Evaluation) -> float:
        """The decrease of vᵀPv the step's linear model predicts from the state it started
        at (:func:`._gain.predicted_decrease`)."""
        st, ap = self._gain_from
        design = None if ap is None else ap.A_csr
        dc, dp, da, local = step.data[0], step.data[1], step.data[2], step.data[5]
        return predicted_decrease(self.prob, st, tuple(previous.data), (dc, dp, da), design, local)

    def _point_newton(self, st: BundleState, ev: Evaluation, dc: F64, dp: F64, da: F64, lam: float):
        """The Newton corrections of the points with a ray beyond the scale given the step's
        ``dc``, ``da`` (:func:`._tail.point_newton`) for a convex loss's robust steps; None
        otherwise (least-squares steps, a redescending loss, steps in frame rotations or
        with auxiliary data)."""
        prob = self.prob
        scale = getattr(ev.data, "scale", None)
        if (
            not self.loss_on
            or self.switch_pending
            or self.loss.redescending
            or self.search_off
            or scale is None
            or prob.aux
            or self.is_local(ev)
        ):
            return None
        rw, Je, Jp = ev.data
        return point_newton(prob, self.loss, self.base_weight, st, (rw, Je, Jp, scale), dc, da, lam)

    def _sigma_correction(self, dc: F64, dp: F64, da: F64) -> float:
        """:meth:`_correction` by the diagonals of the last solve's normal equations."""
        dU, dV, dF = self._sigma
        return max(
            float(np.max(np.abs(dc) * np.sqrt(dU), initial=0.0)),
            float(np.max(np.abs(dp) * np.sqrt(dV), initial=0.0)),
            float(np.max(np.abs(da) * np.sqrt(dF), initial=0.0)) if dF is not None else 0.0,
        )

    def _dx(self, dc: F64, dp: F64, da: F64) -> F64 | None:
        """The correction in the layout of x (zeros for fixed points), if kept."""
        if not self.keep_x:
            return None
        dpa = np.zeros((self.prob.block.n_points, 3))
        dpa[self.prob.points.unknown] = dp
        return np.concatenate([dc.ravel(), dpa.ravel(), da[: self.prob.q]])

    def _correction(self, ne, dc: F64, dp: F64, da: F64) -> float:
        """The largest correction in units of its conditional σ (the stopping measure)."""
        return max(
            float(np.max(np.abs(dc) * np.sqrt(ne.diagU), initial=0.0)),
            float(np.max(np.abs(dp) * np.sqrt(ne.diagV), initial=0.0)),
            float(np.max(np.abs(da) * np.sqrt(ne.diagF), initial=0.0))
            if self.prob.q or self.prob.na
            else 0.0,
        )

    def _chord(self, st: BundleState, rw: F64, Je: F64, Jp: F64, local: bool):
        """A chord step by :attr:`chord_factor` (``options.chord_reuse``) at ``st``:
        (correction, normal equations, dc, dp, da, factor), or None when its correction
        is not below ``options.chord_contraction`` times the last accepted one.

        ``local``: the Jacobian at ``st`` is by rotations of the image frames. A factor
        of such a step serves a step in ω, φ, κ through the map A of
        :func:`~orientviz.bundle._local_rotation.angle_map` at ``st``: J_θ = J_δ·T with
        T = diag(I, A) per image, so N_θ = Tᵀ N_δ T and the step is
        dθ = T⁻¹ N_δ⁻¹ T⁻ᵀ g_θ — the gradient's angle rows A⁻ᵀ g_θ, the solution's
        A⁻¹ δ (:meth:`BundleProblem.chord_normal` ``rot``).
        """
        prob = self.prob
        fac, ne_old, old_local = self.chord_factor
        A = angle_map(st.angles, prob.block.sequence) if old_local and not local else None
        if A is not None and not np.all(np.abs(np.linalg.det(A)) > 1e-9):
            return None  # det A = cos φ ("opk"): an image at the gimbal lock of the angles
        ne = prob.chord_normal(st, rw, Je, Jp, ne_old, rot=A)
        dc, dp, da, fac = prob.solve(ne, self.red_names, fac=fac)
        if A is not None:  # back to ω, φ, κ
            dc[:, 3:] = np.linalg.solve(A, dc[:, 3:, None])[:, :, 0]
        rel = self._correction(ne, dc, dp, da)
        if not rel < prob.options.chord_contraction * self.last_correction:
            return None
        return rel, ne, dc, dp, da, fac

    def _relative_move(self, st: BundleState | None, dc: F64, dp: F64) -> float:
        """The largest change of a step, centres and points in units of the median ray
        length (of a sample of the rays), angles in rad (the measure of
        ``options.chord_reuse`` and ``options.ap_reuse``)."""
        prob = self.prob
        if self.ray_length is None:  # from the first iterate that gets here
            obs = prob.obs  # every k-th ray, at most ~8000: a scale, not a statistic
            k = max(1, obs.point.size // 8192)
            d = st.xyz[obs.point[::k]] - st.X0[obs.image[::k]]
            self.ray_length = float(np.sqrt(np.median(np.sum(d * d, axis=1))))
        L = self.ray_length
        if not L > 0:  # no scale (a degenerate block): nothing may be reused
            return np.inf
        return max(
            float(np.max(np.abs(dc[:, :3]), initial=0.0)) / L,
            float(np.max(np.abs(dc[:, 3:]), initial=0.0)),
            float(np.max(np.abs(dp), initial=0.0)) / L,
        )

    def apply(self, st: BundleState, step: Step) -> BundleState:
        dc, dp, da = step.data[:3]
        local, newton = step.data[5], step.data[6]
        images = None
        if newton is not None:  # each point's correction by its own search (._tail)
            # the new image parameters formed once: the search's projection table of them
            # serves the evaluation of the new iterate (prob.run.image_table)
            images = (st.X0 + dc[:, :3], st.angles + dc[:, 3:])
            dp, self.points_moved, self.search_gain = point_search(
                self.prob, self.loss, self.base_weight, st, dc, da, dp, newton, images
            )
            step.data = (dc, dp, da) + step.data[3:6] + (None,)
            step.max_correction = self.last_rel = self._sigma_correction(dc, dp, da)
            step.dx = self._dx(dc, dp, da)
        self.depths_moved = 0
        if self._held is not None and not (local or self.prob.aux):
            # the held points' depths sought alone (._depth): the move applied, the step's
            # own dp kept for its model and stopping measure (the depth is no unknown of
            # the held step)
            if images is None:
                images = (st.X0 + dc[:, :3], st.angles + dc[:, 3:])
            weight = self.base_weight if self.loss is not None else self.prob.obs.weight
            loss = self.loss if self.loss_on else None
            dp, self.depths_moved, _ = depth_search(
                self.prob, loss, weight, st, dc, da, dp, self._held, images
            )
            if self.depths_moved and step.dx is not None:
                step.dx = self._dx(dc, dp, da)
        new = self.prob.apply(st, dc, dp, da, local=local, images=images)
        if local and step.dx is not None:  # the history records the change of the angles
            step.dx.reshape(-1)[: 6 * self.prob.m].reshape(-1, 6)[:, 3:] = new.angles - st.angles
        return new

    def snapshot(self, st: BundleState) -> F64:
        return self.prob.flat(st) if self.keep_x else np.empty(0)

    def accepted(self, it: int, step: Step, lam: float, previous: Evaluation) -> None:
        prob = self.prob
        dc, dp, _, fac, ne, local, _ = step.data
        self.poor_step = self._poor_step(step, previous)
        # a least-squares step shortened by its damping that does not meet the tolerance:
        # its small decrease of vᵀPv is the damping's (no ftol stop; the tol stop is not
        # affected: a step below the tolerance may stop the run)
        self.damped_step = (
            self.loss is None
            and lam >= STOP_MAX_LAMBDA
            and not step.max_correction < prob.options.tol
        )
        modelled = self._modelled_warm_up(step, previous)
        gain_from, self._gain_from = self._gain_from, None  # (not kept beyond the step)
        if self.loss_on and not self.switch_pending and previous.cost > 0:  # a robust step
            self.robust_tail = (previous.cost - self.pending_cost) < ROBUST_TAIL * previous.cost
            ratio = 0.0  # (a redescending loss keeps ω = 1.5: its tails were not measured)
            if self.robust_tail and not self.loss.redescending:
                ratio = self._curvature_ratio(step, previous, gain_from)
            self._ratios = (self._ratios[1], ratio)
            self._drops = (self._drops[-1], previous.cost - self.pending_cost)
            small = prob.obs.xy.shape[0] <= SEARCH_GATE_RAYS
            if self.search_gain is not None:  # the points' search: did it pay?
                gain, self.search_gain = self.search_gain, None
                if self._tail_search:  # below ftol·Σρ it can no longer move the run's stop
                    low = small and gain < self.stop_ftol * previous.cost
                    self._search_spent, self._search_low = low and self._search_low, low
                self.search_off = small and gain < SEARCH_GAIN * (previous.cost - self.pending_cost)
            # in the run's tail the search runs in every step (until spent)
            self._tail_search = self.robust_tail and not self._search_spent
            if self._tail_search:
                self.search_off = False
        if self.loss is not None and not self.loss_on:  # no longer poor, or settled?
            drop = (previous.cost - self.pending_cost) / previous.cost if previous.cost > 0 else 0.0
            settled = drop <= (LOSS_SWITCH if self.loss.redescending else LOSS_SWITCH_CONVEX)
            if not self.loss.redescending and drop > LOSS_SWITCH and not self._ls_dropped:
                settled = False  # a first decrease of 1–30 %: the start's misclosures not yet out
            self._ls_dropped = self._ls_dropped or drop > LOSS_SWITCH_CONVEX
            if (
                (self.loss.redescending and not self._poor_sigma0(self.pending_cost))
                or settled
                or modelled
                or step.max_correction < 1.0
            ):
                self.loss_on = self.switch_pending = True
        self.last_correction = step.max_correction
        self.last_cost, self.local_step = self.pending_cost, local
        self.chord_factor, self.chord_pending = self.chord_pending, None
        # the precision may reuse this linearisation when it is the converged one (not one
        # that held points: the precision places them where their depth is defined)
        if (
            self.precision
            and lam == 0
            and ne is not None
            and not (prob.q or prob.aux or local)
            and ne.held is None
        ):
            self.lin = (ne, fac, previous.data[1], previous.data[2])
        if prob.q:
            # after a step that meets the tolerance the border is formed at every iterate
            # (the run ends on a step solved on its own border, see the module docstring)
            self.border_fresh = self.border_fresh or step.max_correction < prob.options.tol
            prob.run.border.reuse = (
                not prob.run.border.hold
                and not self.border_fresh
                and prob.ap.lens is None  # a lens model's design moves with its parameters
                and not self.loss_on  # a robust step's ray weights move with the iterate
                and self._relative_move(None, dc, dp) < prob.options.ap_reuse  # (scale set)
            )
