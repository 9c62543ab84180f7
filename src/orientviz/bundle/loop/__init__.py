"""The bundle's iteration: :func:`bundle_adjust` and its steps.

* :mod:`._adjust` — :func:`bundle_adjust`: checks, the problem, the engine's loop
  (:func:`orientviz.adjust.loop.iterate`), the result;
* :mod:`._steps` — :class:`BundleSteps`: evaluate, solve, apply and accept a step
  (damping, chord steps, rotations of the image frames, reuse of the border);
* :mod:`._finish` — the :class:`~orientviz.bundle.BundleResult` at the last iterate
  (residuals, check points, precision).
"""

from ._adjust import bundle_adjust
from ._steps import BundleSteps

__all__ = ["bundle_adjust", "BundleSteps"]
