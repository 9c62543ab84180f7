"""The least-squares engine: the one Gauss-Newton/Levenberg-Marquardt loop and the results.

No plotting, no I/O and nothing of blocks or bundles here (dependencies point down:
``tests/core/test_imports.py``). :func:`iterate` is the loop every adjustment runs
(the dense :func:`gauss_newton` and :func:`orientviz.bundle.bundle_adjust`); every solver
returns an :class:`~orientviz.adjust.result.Adjustment`.
"""

from .engine import gauss_newton
from .loop import Damping, Evaluation, IterativeProblem, Run, Step, StopRule, iterate
from .result import Adjustment, Iteration

__all__ = [
    "Adjustment",
    "Damping",
    "Evaluation",
    "IterativeProblem",
    "Iteration",
    "Run",
    "Step",
    "StopRule",
    "gauss_newton",
    "iterate",
]
