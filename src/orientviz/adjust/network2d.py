"""The smallest free network: points in a plane linked by measured distances.

Unknowns x1, y1, x2, y2, … (m); observations the distances s_k between the point pairs
``pairs[k]`` (m). Nothing ties the network to a coordinate frame, so its normal matrix
has the rank defect 3 (two shifts, one rotation; :func:`~orientviz.adjust.datum.helmert_basis`).
Used by lesson 09 to show the datum.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


def distance_equations(pairs: ArrayLike) -> Callable[[F64], tuple[F64, F64]]:
    """``equations(x) -> (s, J)`` of the distances between ``pairs`` (k, 2) of point indices.

    ``x`` holds the coordinates x1, y1, x2, … (m); ``J`` is (k, 2p) with the unit vector
    from point i to j (∂s/∂(xj, yj)) and its negative (∂s/∂(xi, yi)).
    """
    P = np.asarray(pairs, dtype=int)
    if P.ndim != 2 or P.shape[1] != 2 or np.any(P[:, 0] == P[:, 1]):
        raise InputError(
            f"expected pairs of two different point indices, shape (k, 2), got {P.shape}"
        )

    def equations(x: F64) -> tuple[F64, F64]:
        xy = np.asarray(x, dtype=float).reshape(-1, 2)
        d = xy[P[:, 1]] - xy[P[:, 0]]
        s = np.linalg.norm(d, axis=1)
        u = d / s[:, None]
        J = np.zeros((len(P), xy.size))
        rows = np.arange(len(P))
        for k in range(2):
            J[rows, 2 * P[:, 1] + k] = u[:, k]
            J[rows, 2 * P[:, 0] + k] = -u[:, k]
        return s, J

    return equations


def all_pairs_within(xy: ArrayLike, reach: float) -> I64:
    """Index pairs (i < j) of points closer than ``reach`` (m): the measured distances."""
    p = np.asarray(xy, dtype=float)
    i, j = np.triu_indices(len(p), 1)
    keep = np.linalg.norm(p[j] - p[i], axis=1) < reach
    return np.column_stack([i[keep], j[keep]])
