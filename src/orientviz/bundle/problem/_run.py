"""What one bundle adjustment writes while it runs: :class:`BundleRun`.

:class:`~orientviz.bundle.problem.BundleProblem` is constant over the iterations; every
value that changes during a run — the additional parameters' design at the last
iterate, the border's memory, the kept projection — lives in its ``run``, one
:class:`BundleRun` per adjustment (:meth:`BundleProblem.new_run` starts a fresh one).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ._parts import AdditionalBlock, BorderSolver
from ._state import BundleState


@dataclass
class BundleRun:
    """The state of one run of a bundle problem (written by the loop and the solves).

    Attributes
    ----------
    ap : AdditionalBlock
        The additional parameters with their design at :attr:`design_at` (a lens model's
        design moves with the iterate; a linear set keeps the problem's).
    design_at : BundleState or None
        The iterate of ``ap``'s design (lens models).
    border : BorderSolver
        What the solve of the additional parameters' border remembers between
        iterations (hold, reuse, the last E and F, the preconditioner, the log).
    projection : tuple or None
        (iterate, :class:`~orientviz.bundle.model.RayProjection`) kept by
        :meth:`BundleProblem.residuals` ``keep=True`` for the next call at that iterate.
    projected : tuple or None
        (iterate, image coordinates (n, 2) mm of the adjusted rays without additional
        parameters) of the last evaluation by the collinearity kernel (the result's
        residuals reuse them).
    image_table : tuple or None
        (X0, angles, the kernel's per-image table of them) formed for some rays of an
        iterate not yet evaluated (a robust step's point search, at the step's new image
        parameters): :meth:`BundleProblem.residuals` of an iterate with these very arrays
        takes the table instead of forming it again.
    """

    ap: AdditionalBlock
    design_at: BundleState | None = None
    border: BorderSolver = field(default_factory=BorderSolver)
    projection: tuple | None = None
    projected: tuple | None = None
    image_table: tuple | None = None
