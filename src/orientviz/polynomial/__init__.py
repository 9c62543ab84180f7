"""Polynomial strip and block adjustment.

Strips are chained from the stereo models (:func:`form_strips` → :class:`Strip`), then
adjusted by conformal planimetric and height polynomials per strip
(:func:`polynomial_adjust`). The method lives in the private ``_adjust``.
"""

from ._adjust import PolynomialResult, Strip, form_strips, polynomial_adjust

__all__ = ["PolynomialResult", "Strip", "form_strips", "polynomial_adjust"]
