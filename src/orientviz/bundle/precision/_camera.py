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

from ..problem._camera_blocks import dense_blocks
from ._pairs import ray_cofactors
from ._store import store_precision

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
    eye = np.eye(d * m, order="F")  # (LAPACK's layout: solved in place, not copied first)
    Z = scipy.linalg.cho_solve(c, eye, overwrite_b=True, check_finite=False)
    Z4 = Z.reshape(m, d, m, d)
    Zblk = Z4[S.block_i, :, S.block_k, :]  # (blocks, d, d)
    own = np.arange(m)
    Qcc = Z4[own, :, own, :]  # (m, d, d)
    # per ray (observation order): T = W V⁻¹ (d × 3), zero for rays of fixed points
    oi = prob.obs.image
    n_used = oi.size
    if ne.rays.size == n_used and np.array_equal(ne.rays, np.arange(n_used)):
        T = cb.T  # the track order is the rays' order (read only here)
    else:
        T = np.zeros((n_used, d, 3))
        T[ne.rays] = cb.T
    # the rays' weighted design [P½J_e | P½A] (n, 2, d) and P½J_p as the normal equations
    # were formed from them; Q_pp and the gains K of each ray on its image's unknowns
    # (d × 2) and on its point (3 × 2)
    Jd, Jpw = cb.Jc, cb.Jp
    if Jd is None:
        sw = prob.obs.weight[:, :, None]
        Jd = np.empty((n_used, 2, d))
        np.multiply(Je, sw, out=Jd[:, :, :6])
        Jd[:, :, 6:] = ap.Aw
        Jpw = Jp * sw
    Qpp, Kd, Kp, H = ray_cofactors(S, Zblk, T, ne.Vinv, Qcc, oi, Jd, Jpw)
    # the cameras' cofactors in the border's order (group g: image i with group[i] = g)
    at = np.empty(m, np.int64)
    at[ap.group] = own
    Faa = Z4[at][:, 6:, :, 6:][:, :, at].reshape(m * k, m * k)
    store_precision(
        res, prob, H=H, Qpp=Qpp, Qext=np.ascontiguousarray(Qcc[:, :6, :6]),
        pairs=Zblk[:, :6, :6], Faa=Faa, Ke=Kd[:, :6], Kp=Kp,
    )  # fmt: skip
