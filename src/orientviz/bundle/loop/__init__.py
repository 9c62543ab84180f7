"""The bundle's iteration: :func:`bundle_adjust` and its steps.

* :mod:`._adjust` — :func:`bundle_adjust`: checks, the problem, the engine's loop
  (:func:`orientviz.adjust.loop.iterate`), the result;
* :mod:`._steps` — :class:`BundleSteps`: evaluate, solve, apply and accept a step
  (damping, chord steps, rotations of the image frames, reuse of the border);
* :mod:`._loss` — :class:`RobustLoss`: Huber, Cauchy and soft-L1 losses of a ray,
  minimised inside the loop (``BundleOptions.loss``);
* :mod:`._gain` — the decrease of vᵀPv a step's linear model predicts (a poor step's
  decrease does not stop the run by ``ftol``);
* :mod:`._tail` — a robust run's rays beyond the scale: the tail's per-ray model and
  each point's own Newton correction and search;
* :mod:`._finish` — the :class:`~orientviz.bundle.BundleResult` at the last iterate
  (residuals, check points, precision) and :func:`ray_parallax` (points near infinity).
"""

from ._adjust import bundle_adjust
from ._finish import FAR_PARALLAX, ray_parallax
from ._loss import DEFAULT_SCALE, RobustLoss
from ._steps import BundleSteps

__all__ = [
    "bundle_adjust",
    "BundleSteps",
    "RobustLoss",
    "DEFAULT_SCALE",
    "ray_parallax",
    "FAR_PARALLAX",
]
