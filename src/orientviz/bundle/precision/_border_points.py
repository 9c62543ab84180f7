"""The points' terms of a dense border (auxiliary offsets) at the points it couples.

With a border b (auxiliary offsets and drifts, with or without additional parameters)
handled densely by :func:`orientviz.bundle.precision.bundle_precision`, a point j enters
the border's terms through h_j = (point–border coupling)ᵀ V_j⁻¹ (``hb``, (p, nb, 3)):

* Q_cp(i_b, j) −= Q_ca(i_b) h_j for each ray b of j,
* Q_ap,j = −(Σ_b Q_ca(i_b)ᵀ T_b + Q_aa h_j)   (nb × 3),
* Q_pp,j −= h_jᵀ Q_ap,j.

The first and last change nothing where h_j = 0. An offset couples to the points of its
own rows only (an APR reading's ground point), so without additional parameters most
h_j are zero: :func:`border_point_terms` computes the three terms at the points with
h_j ≠ 0 and leaves Q_ap NaN elsewhere (there it is not read). The products per ray and
the sums over a point's rays are those of the whole computation, in the same order.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


def coupled_rays(pt_starts: I64, vo: I64, pts: I64) -> tuple[I64, I64] | None:
    """The rays of the points ``pts`` (ascending) in point order and their segment starts.

    Parameters
    ----------
    pt_starts : ndarray of int, shape (p,)
        Start of each point's rays in ``vo``.
    vo : ndarray of int, shape (r,)
        The rays of all points in point order.
    pts : ndarray of int, shape (k,)
        Points (ascending).

    Returns
    -------
    (rays, starts) or None
        ``rays`` (observation indices) and the start of each point's rays in them; None
        when one of the points has no ray (its sum would not be empty by reduceat).
    """
    ends = np.append(pt_starts[1:], vo.size)
    cnt = ends[pts] - pt_starts[pts]
    if np.any(cnt <= 0):
        return None
    starts = np.concatenate([[0], np.cumsum(cnt)[:-1]]).astype(np.int64)
    pos = np.repeat(pt_starts[pts] - starts, cnt) + np.arange(int(cnt.sum()))
    return vo[pos], starts


def border_point_terms(
    S, oi: I64, vo: I64, ocol: I64, T: F64, Qca: F64, Faa: F64, hb: F64, Qcp: F64,
    Vinv: F64, every_point: bool = False,
) -> tuple[F64, F64]:  # fmt: skip
    """Q_cp (updated in place), Q_pp and Q_ap of the points with a dense border.

    Parameters
    ----------
    S : ReducedStructure
        ``pt_starts`` (start of each point's rays in ``vo``) and ``n_pt``.
    oi, ocol : ndarray of int, shape (n,)
        Image and point column of each used ray.
    vo : ndarray of int
        The rays of point unknowns in point order.
    T : ndarray, shape (n, 6, 3)
        T = W V⁻¹ per ray.
    Qca : ndarray, shape (m, 6, nb)
        Cofactors images × border (m·border unit).
    Faa : ndarray, shape (nb, nb)
        Cofactors of the border.
    hb : ndarray, shape (p, nb, 3)
        h_j of every point (zero where the point does not couple).
    Qcp : ndarray, shape (n, 6, 3)
        Q_cp per ray without the border's term (m²); the term is subtracted in place.
    Vinv : ndarray, shape (p, 3, 3)
        V_j⁻¹ (m²).
    every_point : bool
        Compute Q_ap at every point (the additional parameters' ray terms read it).

    Returns
    -------
    Qpp : ndarray, shape (p, 3, 3)
        Cofactor blocks of the points (m²).
    Qap : ndarray, shape (p, nb, 3)
        Border × points; NaN at the points with h_j = 0 unless ``every_point``.
    """
    p = S.n_pt
    found = None
    if not every_point:
        pts = np.flatnonzero(hb.reshape(p, -1).any(axis=1))
        found = coupled_rays(S.pt_starts, vo, pts)
    if found is None:  # every point
        pts, rays, starts = np.arange(p), vo, S.pt_starts
    else:
        rays, starts = found
    Qcp[rays] -= Qca[oi[rays]] @ hb[ocol[rays]]
    Qpp = Vinv + np.add.reduceat(T[vo].transpose(0, 2, 1) @ (-Qcp[vo]), S.pt_starts, axis=0)
    Qap = np.full((p, *hb.shape[1:]), np.nan)
    if not pts.size:  # the border couples no point
        return Qpp, Qap
    h = hb[pts]
    Qap_k = -(np.add.reduceat(Qca[oi[rays]].transpose(0, 2, 1) @ T[rays], starts, axis=0) + Faa @ h)
    Qpp[pts] -= h.transpose(0, 2, 1) @ Qap_k
    if found is None:
        return Qpp, Qap_k
    Qap[pts] = Qap_k
    return Qpp, Qap
