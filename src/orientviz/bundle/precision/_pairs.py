"""Image–point cofactors by pairs of rays: Q_cp(i_a, j) = −Σ_b Q_cc(i_a, i_b) T_b.

The blocks Q_cc of the image pairs that share a point (the reduced structure's pairs
i ≤ k, d × d each) and T_b = W_b V_j⁻¹ (d × 3) per ray; for each ray a of a point j the
sum over the point's rays b, formed by pairs of rays in batches.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]


def _block_lookup(st, ca, cb_):
    """Index of block (min, max) for image pairs and whether it must be transposed."""
    m = st.n_cam
    keys = st.block_i * m + st.block_k
    lo, hi = np.minimum(ca, cb_), np.maximum(ca, cb_)
    idx = np.searchsorted(keys, lo * m + hi)
    return idx, ca > cb_


def cofactors_by_pairs(S, Zblk: F64, T: F64, oi, Qcp: F64) -> None:
    """Q_cp for each observation a into ``Qcp`` (n, d, 3): −Σ_b Q(i_a, i_b) T_b over the
    rays b of its point, by pairs of rays (``Zblk`` (blocks, d, d), ``T`` (n, d, 3): d = 6,
    or 6 + k with the cameras in the images' blocks), in batches of whole a-groups of about
    4096 pairs: the (pairs, d, d) gather of a batch (~1.2 MB for d = 6) and its products
    stay in the processor's cache."""
    a, b = S.all_pairs
    # blocks and their transposes side by side: one gather per pair, no masked transpose
    Zboth = np.concatenate([Zblk, Zblk.transpose(0, 2, 1)])
    seg = np.append(S.all_pairs_starts, a.size)
    s0, chunk = 0, 4096
    while s0 < S.all_pairs_starts.size:
        s1 = max(int(np.searchsorted(seg, seg[s0] + chunk, side="right")) - 1, s0 + 1)
        sl = slice(seg[s0], seg[s1])
        idx, tr = _block_lookup(S, oi[a[sl]], oi[b[sl]])
        Qab = Zboth[idx + tr * Zblk.shape[0]]
        QT = Qab @ T[b[sl]]  # Q(i_a, i_b) T_b
        Qcp[S.pt_obs[s0:s1]] = -np.add.reduceat(QT, S.all_pairs_starts[s0:s1] - seg[s0], axis=0)
        s0 = s1


def point_cofactors(Vinv: F64, T: F64, Qcp: F64, vo, pt_starts) -> F64:
    """Q_pp,j = V_j⁻¹ − Σ_b T_bᵀ Q_cp(i_b, j) over the rays b of each point unknown j
    (``vo``: the rays of point unknowns in point order, ``pt_starts`` each point's first);
    shape (p_var, 3, 3)."""
    return Vinv + np.add.reduceat(T[vo].transpose(0, 2, 1) @ (-Qcp[vo]), pt_starts, axis=0)
