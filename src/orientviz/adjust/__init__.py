"""The least-squares engine: the one Gauss-Newton/Levenberg-Marquardt loop and the results.

No plotting, no I/O and nothing of blocks or bundles here (dependencies point down:
``tests/core/test_imports.py``). :func:`iterate` is the loop every adjustment runs
(the dense :func:`gauss_newton` and :func:`orientviz.bundle.bundle_adjust`); every solver
returns an :class:`~orientviz.adjust.result.Adjustment`.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

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


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module, __name__), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return list(__all__)


if TYPE_CHECKING:  # for type checkers and editors; nothing is imported at run time
    from .engine import gauss_newton
    from .loop import Damping, Evaluation, IterativeProblem, Run, Step, StopRule, iterate
