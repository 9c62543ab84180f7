"""Approximate values from scratch: orientations and points from the image coordinates.

The bundle adjustment needs a start near its optimum. :func:`approximate_values` builds
one for a :class:`~orientviz.block.Block` from its image coordinates and control alone
(a seed pair by the essential matrix, waves of resections and intersections, short
bundle adjustments of the oriented part, a similarity onto the datum). It stands above
the solvers it uses (:mod:`orientviz.orientation`, :mod:`orientviz.bundle`); the
modules behind this face:

* ``_values.py`` — :func:`approximate_values` and the datum step (``into_frame``);
* ``_growth.py`` — the seed pair and the waves (``Growth``);
* ``_batch.py`` — the stacked Levenberg-Marquardt resection of one wave;
* ``_front.py`` — the local bundle of the last waves' images and points.
"""

from ._values import approximate_values

__all__ = ["approximate_values"]
