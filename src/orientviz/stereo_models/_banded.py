"""Helpers of the banded path of :func:`orientviz.stereo_models.scalar_cofactors`.

:func:`band_order` chooses the order of the reduced unknowns that gives the band of S
(and of the pairs of unknowns the groups read) its smallest half-width: reverse
Cuthill-McKee, or, with the models' centres, the models numbered across the strips
(:func:`orientviz.bundle.reduced.geometric_orderings`). :func:`group_products` reads the
groups' cofactor blocks Gᵀ S⁻¹ G off the band of the inverse.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.csgraph import reverse_cuthill_mckee

from ..bundle.reduced import geometric_orderings

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


def group_products(Gc: sp.csc_matrix, grp: I64, Zb: F64, pos: I64, s: F64) -> F64:
    """Gᵀ S⁻¹ G at each group's columns, (g, k, k): per group the rows R its columns of G
    read, S⁻¹[R, R] from the band ``Zb`` of the scaled inverse (positions ``pos``, Jacobi
    scale ``s``: S⁻¹ = s (s S s)⁻¹ s) and the dense product with G[R, group]."""
    g, k = grp.shape
    n = Gc.shape[0]
    ptr, rows, vals = Gc.indptr, Gc.indices, Gc.data
    gi, a = np.nonzero(grp >= 0)
    t = grp[gi, a]
    cnt = ptr[t + 1] - ptr[t]
    e = np.repeat(np.arange(t.size), cnt)  # every entry of every column of every group
    ie = ptr[t][e] + np.arange(e.size) - (np.cumsum(cnt) - cnt)[e]
    eg, er = gi[e], rows[ie]
    keys, inv = np.unique(eg * n + er, return_inverse=True)  # the rows of each group
    ug, ur = np.divmod(keys, n)
    slot = np.arange(keys.size) - np.searchsorted(ug, ug)
    r = int(slot.max()) + 1 if keys.size else 1
    R = np.zeros((g, r), np.int64)
    R[ug, slot] = ur
    has = np.zeros((g, r), bool)
    has[ug, slot] = True
    Gg = np.zeros((g, r, k))
    np.add.at(Gg, (eg, slot[inv.reshape(-1)], a[e]), vals[ie])
    pr = pos[R]
    both = has[:, :, None] & has[:, None, :]
    d = np.where(both, np.abs(pr[:, :, None] - pr[:, None, :]), 0)  # ≤ kd: graph edges
    Z = Zb[np.minimum(pr[:, :, None], pr[:, None, :]), d]
    sr = np.where(has, s[R], 0.0)
    Z *= sr[:, :, None] * sr[:, None, :]
    return Gg.transpose(0, 2, 1) @ Z @ Gg


def band_order(graph: sp.csr_matrix, centres: F64 | None) -> tuple[I64, int]:
    """The narrowest band's order of the reduced unknowns on ``graph``: reverse
    Cuthill-McKee, or the models (``centres``) numbered across the strips; (position of
    each unknown, half-band)."""
    n = graph.shape[0]
    perms = [reverse_cuthill_mckee(graph, symmetric_mode=True)]
    if centres is not None and n % len(centres) == 0:
        p = n // len(centres)
        X0 = np.column_stack([centres, np.zeros(len(centres))])
        perms += [(o[:, None] * p + np.arange(p)).ravel() for o in geometric_orderings(X0)]
    P = graph.tocoo()
    best: tuple[I64, int] | None = None
    for perm in perms:
        pos = np.empty(n, np.int64)
        pos[np.asarray(perm, np.int64)] = np.arange(n)
        kd = int(np.max(np.abs(pos[P.row] - pos[P.col]), initial=0))
        if best is None or kd < best[1]:
            best = (pos, kd)
    return best
