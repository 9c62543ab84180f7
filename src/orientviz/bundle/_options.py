"""The bundle's options: one frozen value with every knob of the solver and its default.

:func:`~orientviz.bundle.bundle_adjust` takes ``options=BundleOptions(...)``; its keywords
``max_iter``, ``tol``, ``solver`` and ``history_x`` are shorthands that replace the same
fields of ``options``. Change a field with :func:`dataclasses.replace` or
:meth:`BundleOptions.replace`::

    opts = BundleOptions(tol=1e-3, chord_reuse=0.0)        # every step a Newton step
    res = bundle_adjust(block, options=opts)
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from .reduced import ReducedOptions

#: What ``solver`` may name: the reduced system's solvers, ``"auto"`` (chosen from the
#: structure) and ``"reference"`` (the textbook iteration, :mod:`orientviz.bundle.reference`).
SOLVER_NAMES: tuple[str, ...] = ("auto", "banded", "dense", "sparse", "reference")
#: What ``loss`` may name (:mod:`orientviz.bundle.loop._loss`; ``"none"``: least squares).
LOSSES: tuple[str, ...] = ("none", "huber", "cauchy", "soft_l1")


@dataclass(frozen=True)
class BundleOptions:
    """Knobs of the bundle adjustment (a value: frozen, compared by its fields).

    Attributes
    ----------
    max_iter : int
        Maximum number of Gauss-Newton steps.
    tol : float
        Stop when every correction is below ``tol`` times its a-priori conditional
        σ = 1/√N_ii (dimensionless). The conditional σ is much smaller than the real one
        in a block, so the rule is strict.
    solver : {"auto", "banded", "dense", "sparse", "reference"}
        Solver of the reduced camera system (:mod:`orientviz.bundle.reduced`); ``"auto"``
        chooses from the structure.
    history_x : bool or None
        Keep the full parameter vector in every :class:`~orientviz.adjust.Iteration`
        (None: for blocks of at most ``history_x_limit`` images).
    history_x_limit : int
        Blocks up to this many images keep ``x`` per iteration when ``history_x`` is None.
    poor_start_sigma0 : float
        Above this start σ0 (dimensionless) a singular first normal matrix is blamed on
        the approximations (damped steps are tried) rather than reported as a defect,
        and additional parameters are held at their values in the first step.
    local_sigma0 : float
        Steps rotate the image frames (:mod:`orientviz.bundle.model._local_rotation`)
        while σ0 of the last accepted state is at least this (dimensionless) …
    local_min_correction : float
        … and the last correction was at least this many conditional σ.
    chord_reuse : float
        A plain bundle without precision solves the step after a small one with that
        step's factor (a *chord* step) when that step moved no projection centre or
        point by more than this fraction of the median ray length and no angle by more
        than this (rad). 0 makes every step a Newton step.
    chord_contraction : float
        A chord step must correct by less than this times the step before, else it is
        replaced by a full step at the same iterate (≤ 1/2 keeps the distance to the
        optimum after a chord stop below the tolerance).
    ap_reuse : float
        The border E, F of the additional parameters is reused in the next iteration
        when the last step moved nothing by more than this fraction of the median ray
        length (positions) or this many rad (angles).
    pcg_tol : float
        Relative tolerance of the conjugate gradients that solve the additional
        parameters' border (preconditioned residual norm).
    pcg_stale_steps : int
        More conjugate-gradient steps than this: the preconditioner is formed anew.
    pcg_max_steps : int
        After this many steps the border is solved exactly instead.
    dense_inverse_limit : int
        The precision inverts S densely up to this many unknowns (6m); above, by the
        banded (Takahashi) or sparse selected inverse.
    takahashi_block : int
        Block size (unknowns) of the banded selected inverse.
    reduced : ReducedOptions
        How the reduced system's solver is chosen and diagnosed.
    damping : {"fallback", "trust"}
        The loop's damping (:class:`orientviz.adjust.Damping`): ``"fallback"``
        Gauss-Newton, damped only where a step would raise vᵀPv; ``"trust"``
        Levenberg-Marquardt with a trust-region schedule (λ0 = 1e-4, ÷ 3 per accepted
        step, never 0; the images' blocks damped in their scene's frame), which moves
        weakly determined far points only as far as their rays pull them in each step
        (what imported SfM models use). A point whose rays diverge (they meet behind
        the cameras) recedes along them step by step: its vᵀPv falls towards its value
        at infinity.
    ftol : float
        Also stop when a step lowers vᵀPv by less than ``ftol`` of its value (Ceres's
        function tolerance, dimensionless; 0 = off) — in least squares not on a poor
        step: one that realised less than ¼ of the decrease its linear model predicted,
        that prediction above ``ftol`` (:mod:`orientviz.bundle.loop._gain`).
    loss : {"none", "huber", "cauchy", "soft_l1"}
        Robust loss ρ of each ray's squared standardised misclosure, minimised inside
        the loop (each step's rays weighted by √ρ′; :mod:`orientviz.bundle.loop._loss`);
        such steps converge linearly: a robust run may take 4 × ``max_iter`` steps and
        stops also when Σ ρ falls by less than ``ftol`` of its value (1e-6 if ``ftol``
        is 0, as Ceres).
    loss_scale : float or None
        Its scale a in units of the observations' σ (None: 1.345 Huber and soft-L1,
        2.385 Cauchy).
    """

    max_iter: int = 30
    tol: float = 5e-3
    solver: str = "auto"
    history_x: bool | None = None
    history_x_limit: int = 500
    poor_start_sigma0: float = 30.0
    local_sigma0: float = 30.0
    local_min_correction: float = 10.0
    chord_reuse: float = 1e-3
    chord_contraction: float = 0.5
    ap_reuse: float = 1e-4
    pcg_tol: float = 1e-4
    pcg_stale_steps: int = 12
    pcg_max_steps: int = 40
    dense_inverse_limit: int = 3000
    takahashi_block: int = 96
    reduced: ReducedOptions = field(default_factory=ReducedOptions)
    damping: str = "fallback"
    ftol: float = 0.0
    loss: str = "none"
    loss_scale: float | None = None

    def __post_init__(self) -> None:
        if self.solver not in SOLVER_NAMES:
            raise ValueError(f"expected a solver out of {SOLVER_NAMES}, got {self.solver!r}")
        if self.damping not in ("fallback", "trust"):
            raise ValueError(f"expected damping 'fallback' or 'trust', got {self.damping!r}")
        if not 0.0 <= self.ftol < 1.0:
            raise ValueError(f"expected ftol in [0, 1), got {self.ftol!r}")
        if self.loss not in LOSSES:
            raise ValueError(f"expected a loss out of {LOSSES}, got {self.loss!r}")
        if self.loss_scale is not None and not self.loss_scale > 0:
            raise ValueError(f"expected a positive loss_scale, got {self.loss_scale!r}")

    def replace(self, **changes) -> BundleOptions:
        """A copy with ``changes`` (fields of this class)."""
        return dataclasses.replace(self, **changes)
