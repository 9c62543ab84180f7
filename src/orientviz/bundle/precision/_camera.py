"""Precision of a bundle whose cameras are per image, in blocks of d = 6 + k unknowns.

When every image has a camera of its own (a BAL problem, a COLMAP model with a camera per
image) the bundle solves its reduced system in blocks of an image's exterior orientation
and its camera's k parameters (:mod:`orientviz.bundle.problem._camera_blocks`, S_d of
m·d unknowns, factored densely). The precision then follows from the same blocks, as for a
block without additional parameters with d in place of 6 (:mod:`._precision`):

* Z = S_d⁻¹ (dense; Q_cc of the images' exterior and camera parameters),
* Q_cp(i_a, j) = −Σ_b Z(i_a, i_b) T_b with T_b = W_b V_j⁻¹ (d × 3, W = [J_e | A]ᵀ P J_p),
* Q_pp,j = V_j⁻¹ − Σ_b T_bᵀ Q_cp(i_b, j),
* the ray's 2 × 2 block of J Q Jᵀ with J = [J_e | A | J_p]: redundancy numbers and the
  gains K of a ray on its image's exterior and its point.

The numbers are those of the border form (:func:`._precision.bundle_precision` on E, F and
the group pairs) to rounding; this form needs neither the border's inverse nor its
(point, group) pairs. Units as in :mod:`._precision`.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from .._result import ExteriorPairs, RayGains
from ..problem._camera_blocks import dense_blocks

F64 = NDArray[np.float64]


def camera_precision(res, prob, ne, Je: F64, Jp: F64) -> None:
    """Fill ``res`` as :func:`~orientviz.bundle.precision.bundle_precision` does, from the
    camera blocks of ``ne``.

    Parameters
    ----------
    res : Adjustment
        The bundle result (residual order as in :mod:`orientviz.bundle._result`).
    prob : BundleProblem
        The problem, its cameras in the images' blocks (``prob.camera_blocks``).
    ne : NormalEquations
        Its normal equations at the solution, undamped
        (:func:`~orientviz.bundle.problem._camera_blocks.camera_normal`; ``ne.ext`` the
        blocks).
    Je, Jp : ndarray, shapes (n, 2, 6), (n, 2, 3)
        The rays' Jacobians at the solution (by the exterior orientation and the point).
    """
    cb = ne.ext
    S, ap = prob.reduced, prob.ap
    m, k, d = prob.m, ap.k, cb.d
    # Z = S_d⁻¹ densely (the factor of the iterations is of a damped S_d), its blocks at
    # the structure's image pairs (i ≤ l) and at each image itself
    N = dense_blocks(S, cb.blocks)
    c = scipy.linalg.cho_factor(N, lower=True, overwrite_a=True, check_finite=False)
    Z4 = scipy.linalg.cho_solve(c, np.eye(d * m), check_finite=False).reshape(m, d, m, d)
    Zblk = Z4[S.block_i, :, S.block_k, :]  # (blocks, d, d)
    own = np.arange(m)
    Qcc = Z4[own, :, own, :]  # (m, d, d)
    # per ray (observation order): T = W V⁻¹ (d × 3), zero for rays of fixed points
    oi, ocol = prob.obs.image, prob.obs.column
    n_used = oi.size
    T = np.zeros((n_used, d, 3))
    T[ne.rays] = cb.T
    Qcp = np.zeros((n_used, d, 3))
    _pairs(S, Zblk, T, oi, Qcp)
    vo = prob.obs.var_rays  # the rays of point unknowns, in point order
    Qpp = ne.Vinv + np.add.reduceat(T[vo].transpose(0, 2, 1) @ (-Qcp[vo]), S.pt_starts, axis=0)
    # the rays' weighted design [P½ J_e | P½ A] (n, 2, d) and P½ J_p; the gains K of each
    # ray on its image's unknowns (d × 2) and on its point (3 × 2)
    sw = prob.obs.weight[:, :, None]
    Jd = np.empty((n_used, 2, d))
    np.multiply(Je, sw, out=Jd[:, :, :6])
    Jd[:, :, 6:] = ap.Aw
    Jpv = Jp[vo] * sw[vo]
    JdT, JpvT = Jd.transpose(0, 2, 1), Jpv.transpose(0, 2, 1)
    Kd = Qcc[oi] @ JdT
    Kd[vo] += Qcp[vo] @ JpvT
    Kp = np.zeros((n_used, 3, 2))
    Kp[vo] = Qcp[vo].transpose(0, 2, 1) @ JdT[vo] + Qpp[ocol[vo]] @ JpvT
    # P½ J Q Jᵀ P½ per ray: redundancy numbers 1 − diagonal, and the off-diagonal
    H = Jd @ Kd
    H[vo] += Jpv @ Kp[vo]
    r_img = np.clip(1.0 - np.stack([H[:, 0, 0], H[:, 1, 1]], 1), 0.0, 1.0)
    r_xy = -0.5 * (H[:, 0, 1] + H[:, 1, 0])
    # the cameras' cofactors in the border's order (group g: image i with group[i] = g)
    at = np.empty(m, np.int64)
    at[ap.group] = own
    Faa = Z4[at][:, 6:, :, 6:][:, :, at].reshape(m * k, m * k)
    Qext = np.ascontiguousarray(Qcc[:, :6, :6])
    n = prob.block.n_observations
    rn = np.full((n, 2), np.nan)
    rn[prob.obs.index] = r_img
    out_r = [rn.reshape(-1)]
    # pseudo-observations
    w = prob.points.prior_w > 0
    out_r.append((1.0 - prob.points.prior_w * np.einsum("nii->ni", Qpp))[w])
    cdiag = np.einsum("nii->ni", Qext)
    w = prob.exterior.X0_w > 0
    out_r.append((1.0 - prob.exterior.X0_w * cdiag[:, :3])[w])
    w = prob.exterior.angles_w > 0
    out_r.append((1.0 - prob.exterior.angles_w * cdiag[:, 3:])[w])
    w = ap.w > 0
    out_r.append((1.0 - ap.w * np.diag(Faa))[w])
    rall = np.concatenate(out_r)
    res.redundancy_numbers = rall
    with np.errstate(divide="ignore", invalid="ignore"):
        wres = res.residuals / (res.sigma_obs * np.sqrt(rall))
    res.normalized_residuals = np.where(rall > 1e-10, wres, np.nan)
    p = prob.block.n_points
    Qp_all = np.zeros((p, 3, 3))
    Qp_all[prob.points.unknown] = Qpp
    Qp_all[prob.block.points.role == 2] = np.nan
    res.cofactor_groups["exterior"] = Qext
    res.exterior_pairs = ExteriorPairs(S.block_i * m + S.block_k, Zblk[:, :6, :6])
    res.cofactor_groups["points"] = Qp_all
    res.cofactor_groups["additional"] = Faa
    res.redundancy_check = float(np.nansum(rall))
    rxy = np.full(n, np.nan)
    rxy[prob.obs.index] = r_xy
    res.redundancy_xy = rxy
    gain_e = np.full((n, 6, 2), np.nan)
    gain_e[prob.obs.index] = Kd[:, :6]
    gain_p = np.full((n, 3, 2), np.nan)
    gain_p[prob.obs.index] = Kp
    res.ray_gains = RayGains(gain_e, gain_p)


def _pairs(S, Zblk: F64, T: F64, oi, Qcp: F64) -> None:
    """Q_cp of each ray: −Σ_b Z(i_a, i_b) T_b over the rays b of its point, by pairs."""
    a, b = S.all_pairs
    Zboth = np.concatenate([Zblk, Zblk.transpose(0, 2, 1)])
    m = S.n_cam
    keys = S.block_i * m + S.block_k
    seg = np.append(S.all_pairs_starts, a.size)
    s0, chunk = 0, 4096
    while s0 < S.all_pairs_starts.size:
        s1 = max(int(np.searchsorted(seg, seg[s0] + chunk, side="right")) - 1, s0 + 1)
        sl = slice(seg[s0], seg[s1])
        ca, cb_ = oi[a[sl]], oi[b[sl]]
        lo, hi = np.minimum(ca, cb_), np.maximum(ca, cb_)
        idx = np.searchsorted(keys, lo * m + hi) + (ca > cb_) * Zblk.shape[0]
        QT = Zboth[idx] @ T[b[sl]]
        Qcp[S.pt_obs[s0:s1]] = -np.add.reduceat(QT, S.all_pairs_starts[s0:s1] - seg[s0], axis=0)
        s0 = s1
