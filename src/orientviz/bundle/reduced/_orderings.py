"""Image orders that give the reduced camera system S a narrow band.

Ackermann's bandwidth minimisation: a block of aerial strips numbered *across* the
strips (the shorter way through the block) gives S a band about two columns of images
wide. :func:`geometric_orderings` proposes such numberings from the projection centres;
:class:`~orientviz.bundle.reduced.ReducedStructure` takes the narrowest band of these and
reverse Cuthill-McKee.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


def geometric_orderings(X0: F64, pairs: tuple[I64, I64] | None = None) -> list[I64]:
    """Candidate image orders from projection centres (m, 3) in m: numbering across strips.

    Ackermann's rule for a narrow band: number the images along the *shorter* way
    through the block. The centres are projected on their two principal horizontal
    axes; along one axis the images are grouped into columns wherever consecutive
    coordinates jump by more than half the typical image spacing (median
    nearest-neighbour distance), and numbered column by column, sorted along the other
    axis inside a column. Both axes are returned.
    """
    xy = np.asarray(X0, dtype=float)[:, :2]
    if xy.shape[0] < 3:
        return []
    c = xy - xy.mean(axis=0)
    _, _, Vt = np.linalg.svd(c, full_matrices=False)
    if pairs is not None:  # nearest neighbour among the images sharing points
        i, k = pairs
        off = i != k
        dist = np.hypot(*(xy[i[off]] - xy[k[off]]).T)
        nn = np.full(xy.shape[0], np.inf)
        np.minimum.at(nn, i[off], dist)
        np.minimum.at(nn, k[off], dist)
        base = float(np.median(nn[np.isfinite(nn)])) if np.isfinite(nn).any() else 0.0
    else:
        from scipy.spatial import cKDTree

        d, _ = cKDTree(xy).query(xy, k=2)
        base = float(np.median(d[:, 1]))
    if not base > 0:
        return []
    out = []
    for ax in (0, 1):
        a = c @ Vt[ax]
        b = c @ Vt[1 - ax]
        o = np.argsort(a, kind="stable")
        col = np.empty(a.size, np.int64)
        col[o] = np.cumsum(np.concatenate([[0], np.diff(a[o]) > 0.5 * base]))
        out.append(np.lexsort((b, col)).astype(np.int64))
    return out
