"""Per-ray products of the bundle's normal equations, and their sums per image and point.

A ray contributes J_pᵀ P J_p (3 × 3) to its point's block of the normal equations (J_p
the 2 × 3 Jacobian by the point, weighted by P½). Formed as a stacked matrix product of
the transposed view (``(n, 3, 2) @ (n, 2, 3)``) numpy pays about 90 ns per ray, as six
products of whole columns (:func:`gram3`, the distinct entries only) about 15 ns; the
6 × 3 couplings and 6 × 6 image blocks keep their BLAS-backed products, which are as
fast as columns there (numpy's inner loops over a last axis of 3 or 6 are slow). The sums
over the rays of each image or point are products with a sparse 0/1 matrix
(:class:`RaySums`): one pass over the rays, 2-3 × faster than ``np.add.reduceat`` over
the first axis of a (n, k) array.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: The six distinct entries (row, column) of a symmetric 3 × 3 block, in storage order.
SYM3 = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))


@dataclass(frozen=True)
class RaySums:
    """Sums of per-ray rows over the rays of each image and of each point unknown.

    Attributes
    ----------
    by_image : scipy.sparse.csr_matrix, shape (m, n)
        1 where the ray (column) belongs to the image (row).
    by_point : scipy.sparse.csr_matrix, shape (p_var, n_var)
        1 where the ray belongs to the point unknown; the columns are the rays of point
        unknowns in point order (``ImageObservations.var_rays``).
    """

    by_image: sp.csr_matrix
    by_point: sp.csr_matrix

    @classmethod
    def of(
        cls, image: I64, m: int, pt_starts: I64, n_var: int, order: I64 | None = None
    ) -> RaySums:
        """From the image of each ray (``order``: the rays sorted by image, if known) and
        the first ray of each point unknown (its rays consecutive)."""
        n = image.size
        order = np.argsort(image, kind="stable") if order is None else order
        indptr = np.concatenate([[0], np.cumsum(np.bincount(image, minlength=m))])
        by_image = sp.csr_matrix((np.ones(n), order, indptr), shape=(m, n))
        p = pt_starts.size
        by_point = sp.csr_matrix(
            (np.ones(n_var), np.arange(n_var), np.append(pt_starts, n_var)), shape=(p, n_var)
        )
        return cls(by_image, by_point)


def gram3(J: F64) -> F64:
    """The six distinct entries (:data:`SYM3`) of Jᵀ J per ray: (n, 6) from J (n, 2, 3)."""
    out = np.empty((J.shape[0], 6))
    for k, (i, j) in enumerate(SYM3):
        np.multiply(J[:, 0, i], J[:, 0, j], out=out[:, k])
        out[:, k] += J[:, 1, i] * J[:, 1, j]
    return out


def sym3(entries: F64) -> F64:
    """Symmetric 3 × 3 blocks (p, 3, 3) from their six distinct entries (p, 6)."""
    out = np.empty((entries.shape[0], 3, 3))
    for k, (i, j) in enumerate(SYM3):
        out[:, i, j] = entries[:, k]
        out[:, j, i] = entries[:, k]
    return out
