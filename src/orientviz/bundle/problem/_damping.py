"""Levenberg-Marquardt damping of the image blocks in the frame of the image's scene.

Marquardt's damping adds λ·diag(N) to the normal matrix: it penalises a step by
λ·Σ N_ii δ_i², which depends on the coordinates the step is taken in. In the bundle's
(X0, ω, φ, κ) an image that turns about the scene it sees (the weak motion of a
narrow-angle close-range image: the image barely changes) is a large change of X0 *and*
of the angles, and the damping holds it back; in the coordinates of the scene as the
camera sees it, τ = Rᵀ(c − X0) (camera frame, c a point of the scene), and the angles,
the same motion changes the angles only. SfM solvers damp in such coordinates (Ceres
on COLMAP's and BAL's cam_from_world translation t = −Rᵀ X0 with c the world origin).

:func:`image_damping` damps each image's 6 × 6 block U by λ·Tᵀ diag(T⁻ᵀ U T⁻¹) T — the
Marquardt damping diag × (1 + λ) in the coordinates z = (τ, ω, φ, κ) with dz = T d(X0,
ω, φ, κ) — with c the median of the image's points at the start
(:func:`scene_centres`): near the scene whatever the datum's origin (a geodetic frame's
origin lies far away). The steps' fixed point is unchanged: only the damped steps differ.
A step whose Jacobian is by rotations of the image frames (a poor start without a camera
model, :mod:`orientviz.bundle.model._local_rotation`) is damped with the same map T of
ω, φ, κ: positive definite as any such damping, but not exactly the scene frame's.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...rotation import matrix_derivatives, matrix_from_opk

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


#: :func:`scene_centres` takes the median of at most 2 × this many rays of an image
#: (every k-th of a longer list).
SCENE_SAMPLE: int = 256


def scene_centres(image: I64, point: I64, xyz: F64, X0: F64, order: I64 | None = None) -> F64:
    """The median of each image's observed points (m, 3), per coordinate, m — a point of
    the scene the image sees, unmoved by a few far points (points near infinity, gross
    errors of a start); of every k-th point of an image with more than 2 ×
    :data:`SCENE_SAMPLE`. An image without points with finite coordinates gets its
    projection centre (its damping is then that of the centre's coordinates turned into
    the camera frame).

    Parameters
    ----------
    image, point : ndarray of int, shape (n,)
        Image and point of each observation.
    xyz : ndarray, shape (p, 3)
        Point coordinates (m).
    X0 : ndarray, shape (m, 3)
        Projection centres (m).
    order : ndarray of int, shape (n,), optional
        ``np.argsort(image, kind="stable")`` if known.
    """
    m = X0.shape[0]
    out = X0.copy()
    cnt = np.bincount(image, minlength=m)
    if order is None:
        order = np.argsort(image, kind="stable")
    pos = np.arange(image.size) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    # every k-th ray of an image with more than 2 × SCENE_SAMPLE (a scale, not a statistic)
    keep = pos % np.repeat(np.maximum(cnt // SCENE_SAMPLE, 1), cnt) == 0
    sel = order[keep]
    P = xyz[point[sel]]
    ok = np.all(np.isfinite(P), axis=1)
    img, P = image[sel[ok]], P[ok]  # by image
    if not img.size:
        return out
    cnt = np.bincount(img, minlength=m)
    pos = np.arange(img.size) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    # each image's points side by side, padded with +inf, sorted per coordinate
    Q = np.full((3, m, int(cnt.max())), np.inf)
    Q[:, img, pos] = P.T
    Q.sort(axis=2)
    has = np.flatnonzero(cnt)
    lo, hi = (cnt[has] - 1) // 2, cnt[has] // 2  # the middle one (two for an even count)
    out[has] = 0.5 * (Q[:, has, lo] + Q[:, has, hi]).T
    return out


def image_damping(
    U: F64, lam: float, X0: F64, angles: F64, centres: F64, sequence: str, metric: F64 | None = None
) -> None:
    """Add λ·Tᵀ diag(T⁻ᵀ M T⁻¹) T to every image block of ``U`` (m, 6, 6), in place.

    Parameters
    ----------
    U : ndarray, shape (m, 6, 6)
        The images' blocks of the normal matrix (X0, Y0, Z0 in m, ω, φ, κ in rad).
    lam : float
        λ (> 0).
    X0, angles : ndarray, shape (m, 3)
        The iterate's projection centres (m) and angles (rad, ``sequence``).
    centres : ndarray, shape (m, 3)
        The point c of each image's scene (:func:`scene_centres`), m.
    sequence : {"opk", "pok"}
        The block's rotation sequence.
    metric : ndarray, shape (m, 6, 6), optional
        M, the blocks whose diagonal in z is the damping (default: ``U`` itself). The
        bundle passes the rays' part of U: a held coordinate's pseudo-observation
        (σ 1e-6 m: weight 1e12) would otherwise damp, through τ, the image's rotations
        by its weight; the pseudo-observations are damped × (1 + λ) in their own
        coordinates instead.
    """
    om, ph, ka = angles[:, 0], angles[:, 1], angles[:, 2]
    R = matrix_from_opk(om, ph, ka, sequence)
    D = np.stack(matrix_derivatives(om, ph, ka, sequence), axis=1)  # (m, θ, 3, 3)
    v = centres - X0
    # dτ = −Rᵀ dX0 + Σ_θ (∂R/∂θ)ᵀ (c − X0) dθ;  the angles unchanged
    T = np.zeros((U.shape[0], 6, 6))
    T[:, :3, :3] = -R.transpose(0, 2, 1)
    T[:, :3, 3:] = np.einsum("mtji,mj->mit", D, v)
    T[:, 3:, 3:] = np.eye(3)
    # T⁻¹ = [[−R, R·B], [0, I]] with B = T[:3, 3:]
    Ti = np.zeros_like(T)
    Ti[:, :3, :3] = -R
    Ti[:, :3, 3:] = R @ T[:, :3, 3:]
    Ti[:, 3:, 3:] = np.eye(3)
    M = U if metric is None else metric
    dz = np.einsum("mai,mab,mbi->mi", Ti, M, Ti)  # diag(T⁻ᵀ M T⁻¹)
    U += lam * np.einsum("mai,ma,maj->mij", T, dz, T)
