"""What every precision path hands to the bundle result.

:func:`ray_blocks` forms each ray's gains and its 2 × 2 block of P½ J Q Jᵀ P½ from the
cofactors; :func:`store_precision` turns a path's cofactors and ray blocks into the result's fields:
the redundancy numbers of the image coordinates and of the pseudo-observations (weighted
points, observed projection centres and attitudes, additional parameters), the normalised
residuals, the cofactor groups, the image pairs' blocks and the rays' gains.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from .._result import ExteriorPairs, RayGains

F64 = NDArray[np.float64]

#: Stacked products over fewer terms than this give the same numbers whether a factor is a
#: transposed view or a contiguous copy of it (OpenBLAS's small-matrix kernels add an
#: entry's products in order either way; the sweeps are in benchmarks/README.md, the
#: precision's layouts); the precision multiplies such factors as contiguous copies,
#: which BLAS reads faster, and keeps the views beyond.
LAYOUT_FREE_TERMS: int = 16


def fast_layout(B: F64, terms: int) -> F64:
    """``B`` as a contiguous array when products over ``terms`` terms give the same
    numbers in either layout (:data:`LAYOUT_FREE_TERMS`), else ``B`` itself."""
    return np.ascontiguousarray(B) if terms < LAYOUT_FREE_TERMS else B


def ray_blocks(
    Qimg: F64, img, Qcp: F64, Qpp: F64, Jc: F64, Jpv: F64, vo, pcol, JcT: F64 | None = None,
    JpvT: F64 | None = None, out: tuple[F64, F64, F64] | None = None,
) -> tuple[F64, F64, F64]:  # fmt: skip
    """The rays' gains and their blocks of P½ J Q Jᵀ P½, from the cofactors.

    Parameters
    ----------
    Qimg : ndarray, shape (m, d, d)
        The cofactor block of each image's unknowns (d = 6, or 6 + k with its camera).
    img : ndarray of int, shape (n,)
        Each ray's image: its block ``Qimg[img]`` is gathered only for the one product
        that reads it (an (n, d, d) array is the largest of this step).
    Qcp : ndarray, shape (n, d, 3)
        Q_cp of each ray (its image with its point; rows of fixed points unused).
    Qpp : ndarray, shape (p_var, 3, 3)
        Cofactors of the point unknowns.
    Jc : ndarray, shape (n, 2, d)
        The rays' weighted design by their image unknowns.
    Jpv : ndarray, shape (n_var, 2, 3)
        The weighted point Jacobians of the rays of point unknowns (``vo``).
    vo : slice or ndarray of int
        The rays of point unknowns (any order; a slice reads views); ``pcol`` their
        point unknowns.
    JcT, JpvT : ndarray, shapes (n, d, 2), (n_var, 3, 2), optional
        ``Jc`` and ``Jpv`` transposed (:func:`fast_layout`; made here when not given).
    out : tuple of ndarray, optional
        Where ``(Kc, Kp, H)`` are written (``Kp`` zero at the rays outside ``vo``).

    Returns
    -------
    (Kc, Kp, H) : ndarrays, shapes (n, d, 2), (n, 3, 2), (n, 2, 2)
        The gains K = Q J_wᵀ of each ray on its image unknowns and its point, and
        J_w K (the ray's 2 × 2 block of P½ J Q Jᵀ P½).
    """
    # the transposed designs as contiguous copies where a stored factor multiplies them
    # (the same numbers, read faster: fast_layout), as views where a transposed one does
    if JcT is None:
        JcT = fast_layout(Jc.transpose(0, 2, 1), Jc.shape[2])
    if JpvT is None:
        JpvT = fast_layout(Jpv.transpose(0, 2, 1), 3)
    if out is None:
        n = Jc.shape[0]
        out = np.empty((n, Jc.shape[2], 2)), np.zeros((n, 3, 2)), np.empty((n, 2, 2))
    Kc, Kp, H = out
    np.matmul(np.take(Qimg, img, axis=0), JcT, out=Kc)  # (np.take: a faster gather)
    Qv = Qcp[vo]
    Kc[vo] += Qv @ JpvT
    Kp[vo] = Qv.transpose(0, 2, 1) @ Jc.transpose(0, 2, 1)[vo] + np.take(Qpp, pcol, axis=0) @ JpvT
    np.matmul(Jc, Kc, out=H)
    H[vo] += Jpv @ Kp[vo]
    return Kc, Kp, H


def store_precision(
    res, prob, *, H: F64, Qpp: F64, Qext: F64, pairs: F64, Faa: F64 | None,
    Ke: F64, Kp: F64, auxiliary: Callable[[], None] | None = None,
) -> None:  # fmt: skip
    """Fill ``res`` from a precision path's results.

    Parameters
    ----------
    res : Adjustment
        The bundle result (residual order as in :mod:`orientviz.bundle._result`).
    prob : BundleProblem
    H : ndarray, shape (n_used, 2, 2)
        Each used ray's block of P½ J Q Jᵀ P½: its x, y redundancy numbers are
        1 − the diagonal, the off-diagonal of P½ Q_vv P½ is −(the off-diagonal).
    Qpp : ndarray, shape (p_var, 3, 3)
        Cofactors of the point unknowns (m²).
    Qext : ndarray, shape (m, 6, 6)
        Each image's exterior cofactor block (m², m·rad, rad²).
    pairs : ndarray, shape (blocks, 6, 6)
        The exterior blocks of the image pairs (i ≤ k) of the reduced structure.
    Faa : ndarray, shape (q, q), or None
        Cofactors of the additional parameters (None without them).
    Ke, Kp : ndarray, shapes (n_used, 6, 2), (n_used, 3, 2)
        The rays' gains on their image's exterior orientation and on their point.
    auxiliary : callable, optional
        Called after the cofactor groups are set and before the redundancy's sum is taken
        (the auxiliary data's rows and offsets).
    """
    S = prob.reduced
    r_img = np.clip(1.0 - np.stack([H[:, 0, 0], H[:, 1, 1]], 1), 0.0, 1.0)
    r_xy = -0.5 * (H[:, 0, 1] + H[:, 1, 0])
    n = prob.block.n_observations
    idx = prob.obs.index
    # per observation, NaN for the unused ones (none: every row is written)
    blank = np.empty if idx.size == n else (lambda shape: np.full(shape, np.nan))
    rn = blank((n, 2))
    rn[idx] = r_img
    out_r = [rn.reshape(-1)]
    # pseudo-observations
    w = prob.points.prior_w > 0
    pdiag = np.einsum("nii->ni", Qpp)
    out_r.append((1.0 - prob.points.prior_w * pdiag)[w])
    cdiag = np.einsum("nii->ni", Qext)
    w = prob.exterior.X0_w > 0
    out_r.append((1.0 - prob.exterior.X0_w * cdiag[:, :3])[w])
    w = prob.exterior.angles_w > 0
    out_r.append((1.0 - prob.exterior.angles_w * cdiag[:, 3:])[w])
    if Faa is not None:
        w = prob.ap.w > 0
        out_r.append((1.0 - prob.ap.w * np.diag(Faa))[w])
    rall = np.concatenate(out_r)
    res.redundancy_numbers = rall
    with np.errstate(divide="ignore", invalid="ignore"):
        wres = res.residuals / (res.sigma_obs * np.sqrt(rall))
    res.normalized_residuals = np.where(rall > 1e-10, wres, np.nan)
    # cofactor blocks by result block
    Qp_all = np.zeros((prob.block.n_points, 3, 3))
    Qp_all[prob.points.unknown] = Qpp
    Qp_all[prob.block.points.role == 2] = np.nan
    res.cofactor_groups["exterior"] = Qext
    # Q_cc of every image pair (i ≤ k) that shares a point: key i·m + k (sorted), blocks
    res.exterior_pairs = ExteriorPairs(S.block_i * prob.m + S.block_k, pairs)
    res.cofactor_groups["points"] = Qp_all
    if Faa is not None:
        res.cofactor_groups["additional"] = Faa
    if auxiliary is not None:
        auxiliary()
    res.redundancy_check = float(np.nansum(rall))
    # off-diagonal (x, y) element of P½ Q_vv P½ per image observation: with the diagonal
    # (the redundancy numbers) the 2×2 block of a ray for 2-D outlier tests
    rxy = blank(n)
    rxy[idx] = r_xy
    res.redundancy_xy = rxy
    gain_e = blank((n, 6, 2))
    gain_e[idx] = Ke
    gain_p = blank((n, 3, 2))
    gain_p[idx] = Kp
    res.ray_gains = RayGains(gain_e, gain_p)
