"""The least-squares engine: the one Gauss-Newton/Levenberg-Marquardt loop and the results.

No plotting, no I/O and nothing of blocks or bundles here (dependencies point down:
``tests/core/test_imports.py``). :func:`iterate` is the loop every adjustment runs
(the dense :func:`gauss_newton` and :func:`orientviz.bundle.bundle_adjust`); every solver
returns an :class:`~orientviz.adjust.result.Adjustment`.
"""

from typing import Any

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


def __getattr__(name: str) -> Any:
    """``gauss_newton`` on first use: :mod:`.engine` loads SciPy, which the tables of a
    block (``orientviz.block`` imports :mod:`.result`) and the file importers never need."""
    if name == "gauss_newton":
        from .engine import gauss_newton  # SciPy only when the dense engine is used

        return gauss_newton
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
