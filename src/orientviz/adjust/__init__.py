"""The least-squares engine: the one Gauss-Newton/Levenberg-Marquardt loop and the results.

No plotting, no I/O and nothing of blocks or bundles here (dependencies point down:
``tests/core/test_imports.py``). :func:`iterate` is the loop every adjustment runs
(the dense :func:`gauss_newton` and :func:`orientviz.bundle.bundle_adjust`); every solver
returns an :class:`~orientviz.adjust.result.Adjustment`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..faces import lazy_names
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

#: Names loaded on first use: the tables of a block (``orientviz.block`` imports
#: :mod:`.result`) and the file importers need neither the loop nor :mod:`.engine`
#: (which loads SciPy).
_LAZY = {
    "Damping": ".loop",
    "Evaluation": ".loop",
    "IterativeProblem": ".loop",
    "Run": ".loop",
    "Step": ".loop",
    "StopRule": ".loop",
    "iterate": ".loop",
    "gauss_newton": ".engine",
}


__getattr__ = lazy_names(__name__, _LAZY, globals())


def __dir__() -> list[str]:
    return list(__all__)


if TYPE_CHECKING:  # for type checkers and editors; nothing is imported at run time
    from .engine import gauss_newton
    from .loop import Damping, Evaluation, IterativeProblem, Run, Step, StopRule, iterate
