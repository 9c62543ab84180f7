"""The bundle's precision: cofactor blocks, redundancy numbers, reliability per ray.

* :mod:`._precision` — :func:`bundle_precision`: per-image 6×6 and per-point 3×3
  cofactor blocks from the selected inverse of the reduced system
  (:func:`banded_selected_inverse` for a band), redundancy numbers and normalised
  residuals;
* :mod:`._precision_ap` — the same with a border of additional parameters;
* :mod:`._band` — :class:`BandSolver`: solves with a band factor and many right-hand
  sides (the border S⁻¹E) by products on views of the factor;
* :mod:`._reliability` — internal and external reliability per ray
  (:func:`ray_reliability` → :class:`RayReliability`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...faces import lazy_names
from ._band import BandSolver
from ._precision import banded_selected_inverse, bundle_precision

__all__ = [
    "BandSolver",
    "banded_selected_inverse",
    "bundle_precision",
    "RayReliability",
    "ray_reliability",
]

#: Names loaded on first use: the reliability per ray (and the tests of
#: :mod:`orientviz.adjust.gross` it builds on) only when asked for.
_LAZY = {
    "RayReliability": "._reliability",
    "ray_reliability": "._reliability",
}

__getattr__ = lazy_names(__name__, _LAZY, globals())


def __dir__() -> list[str]:
    return list(__all__)


if TYPE_CHECKING:  # for type checkers and editors; nothing is imported at run time
    from ._reliability import RayReliability, ray_reliability
