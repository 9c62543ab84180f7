"""The least-squares engine: Gauss-Newton/Levenberg-Marquardt, normal equations, precision.

No plotting and no I/O here. Every solver in orientviz returns an
:class:`~orientviz.adjust.result.Adjustment`.
"""

from .engine import gauss_newton
from .result import Adjustment, Iteration

__all__ = ["Adjustment", "Iteration", "gauss_newton"]
