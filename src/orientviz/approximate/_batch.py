"""Many space resections at once: stacked Gauss-Newton for the growth of the approximations.

:func:`orientviz.approximate.approximate_values` orients, in each step of its growth, every
image that sees enough already-intersected points. Instead of one least-squares
resection per image (a Python loop of small solvers), :func:`resect_batch` runs the
Gauss-Newton iteration of the collinearity equations for all of them together: the
rays of all images are one array, each image's 6 × 6 normal equations are summed by
``bincount`` and solved as one stack. The start of each image is the attitude of an
oriented neighbour and the projection centre that best fits the rays with that
attitude (a linear intersection of the rays *backwards* from the object points).

Conventions as in :mod:`orientviz.camera`: image coordinates relative to the principal
point in mm, image plane at z = −c, R turns image vectors into the object frame; the
attitude is updated as R ← R·exp([δ]×) (δ in rad, small rotations about the image axes).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ..orientation.intersection import intersect_rays

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: Gauss-Newton steps of a batch; an image still moving after them is not accepted.
BATCH_ITERATIONS: int = 12
#: An image has converged when its centre moves less than this fraction of its mean
#: object distance and its attitude less than this (rad) in the last step.
CONVERGED: float = 1e-7


def rotate_by(R: F64, delta: F64) -> F64:
    """``R @ exp([δ]×)`` for stacks: Rodrigues' formula of the rotation vectors δ (rad)."""
    th = np.linalg.norm(delta, axis=1)
    k = delta / np.maximum(th, 1e-300)[:, None]
    K = np.zeros((delta.shape[0], 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -k[:, 2], k[:, 1], -k[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = k[:, 2], -k[:, 1], k[:, 0]
    s, c1 = np.sin(th)[:, None, None], (1.0 - np.cos(th))[:, None, None]
    E = np.eye(3)[None] + s * K + c1 * (K @ K)
    return R @ E


def summing(index: I64, n: int) -> sp.csr_matrix:
    """The (n, k) matrix that sums rows of a (k, …) array by ``index``."""
    return sp.csr_matrix(
        (np.ones(index.size), (index, np.arange(index.size))), shape=(n, index.size)
    )


def centres_for_attitudes(img: I64, xy: F64, c: F64, X: F64, R: F64, n: int) -> tuple[F64, F64]:
    """Projection centres (m) that best fit each image's rays for a given attitude.

    With R fixed, the centre of image j lies on every line through an object point
    ``X`` in the direction ``R·(x, y, −c)``: the linear least-squares intersection of
    those lines (:func:`orientviz.orientation.intersection.intersect_rays`). Returns the
    centres (n, 3), NaN where the lines are parallel, and the eigenvalue ratio of each 3 × 3 system.
    """
    d = np.einsum("nij,nj->ni", R[img], np.column_stack([xy, -c]))
    return intersect_rays(X, d, img, n)


def resect_batch(
    img: I64, xy: F64, c: F64, sigma: F64, X: F64, R0: F64, X00: F64
) -> tuple[F64, F64, F64, NDArray[np.bool_]]:
    """Space resection of ``n`` images together (collinearity, Gauss-Newton).

    Parameters
    ----------
    img : ndarray of int, shape (k,)
        Image of each ray, 0 … n − 1 (an image with fewer than 4 rays, i.e. without
        redundancy to check it, is not accepted).
    xy : ndarray, shape (k, 2)
        Image coordinates relative to the principal point (mm).
    c : ndarray, shape (k,)
        Principal distance of the ray's image (mm).
    sigma : ndarray, shape (k, 2)
        A-priori σ of the image coordinates (mm).
    X : ndarray, shape (k, 3)
        Object points (m, any frame).
    R0, X00 : ndarray, shapes (n, 3, 3) and (n, 3)
        Start attitudes (image → object) and centres (m).

    Returns
    -------
    R : ndarray, shape (n, 3, 3)
    X0 : ndarray, shape (n, 3)
        Estimated attitudes and centres (m).
    sigma0 : ndarray, shape (n,)
        σ̂0 of each image's resection (residuals against ``sigma``; NaN for 3 points).
    ok : ndarray of bool, shape (n,)
        Converged, all points in front of the camera, the normal matrix regular and at
        least 4 rays.
    """
    n = R0.shape[0]
    R, X0 = R0.copy(), X00.copy()
    wgt = 1.0 / sigma**2
    scale = (
        np.bincount(img, np.linalg.norm(X - X0[img], axis=1), n)
        / np.maximum(np.bincount(img, minlength=n), 1)
        + 1e-300
    )
    moving = np.ones(n, bool)
    regular = np.ones(n, bool)
    lam = np.full(n, 1e-4)  # Levenberg-Marquardt damping per image
    _, r, _ = linearise(img, xy, c, X, R, X0, jacobian=False)
    cost = _cost(img, r, wgt, n)
    for _ in range(BATCH_ITERATIONS):
        J, r, _ = linearise(img, xy, c, X, R, X0)
        dx, reg = _normal_solve(img, J, r, wgt, n, lam)
        regular &= reg
        dx[~reg | ~moving] = 0.0
        X1, R1 = X0 + dx[:, :3], rotate_by(R, dx[:, 3:])
        _, r1, _ = linearise(img, xy, c, X, R1, X1, jacobian=False)
        cost1 = _cost(img, r1, wgt, n)
        better = cost1 <= cost  # NaN (a point on the image plane) is not better
        X0[better], R[better], cost[better] = X1[better], R1[better], cost1[better]
        lam = np.where(better, np.maximum(lam / 10, 1e-9), lam * 10)
        # converged: the step (taken or not) is below the resolution that matters
        moving &= (
            (np.linalg.norm(dx[:, :3], axis=1) > CONVERGED * scale)
            | (np.linalg.norm(dx[:, 3:], axis=1) > CONVERGED)
            | (lam > 1e-2)
        )  # a short step of a strongly damped image is no convergence
        if not moving.any():
            break
    _, r, front = linearise(img, xy, c, X, R, X0, jacobian=False)
    k = np.bincount(img, minlength=n)
    vtpv = np.bincount(img, (r**2 * wgt).sum(axis=1), n)
    with np.errstate(invalid="ignore", divide="ignore"):
        sigma0 = np.sqrt(vtpv / (2 * k - 6))
    behind = np.bincount(img, ~front, n) > 0
    ok = regular & ~moving & ~behind & np.isfinite(X0).all(axis=1) & (k >= 4)
    return R, X0, sigma0, ok


def linearise(img, xy, c, X, R, X0, jacobian=True):
    """Residuals ``l − f(x)`` (k, 2) mm, the Jacobian (k, 2, 6) and which points lie in front."""
    d = X - X0[img]
    p = np.einsum("nji,nj->ni", R[img], d)  # Rᵀ (X − X0): camera frame
    u, v, w = p[:, 0], p[:, 1], p[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        f = -c[:, None] * p[:, :2] / w[:, None]
    r = xy - f
    front = w < 0
    if not jacobian:
        return None, r, front
    g = np.zeros((img.size, 2, 3))
    g[:, 0, 0] = g[:, 1, 1] = -c / w
    g[:, 0, 2] = c * u / w**2
    g[:, 1, 2] = c * v / w**2
    J = np.empty((img.size, 2, 6))
    J[:, :, :3] = -np.einsum("nij,naj->nai", R[img], g)  # ∂f/∂X0 = −g Rᵀ
    J[:, :, 3:] = np.cross(g, p[:, None, :])  # ∂f/∂δ: g·(p × δ) = δ·(g × p)
    return J, r, front


def _cost(img, r, wgt, n):
    """Each image's weighted square sum of residuals."""
    return np.bincount(img, (r**2 * wgt).sum(axis=1), n)


def _normal_solve(img, J, r, wgt, n, lam):
    """Each image's damped step from its 6 × 6 normal equations; False where they are singular."""
    JwT = (J * wgt[:, :, None]).transpose(0, 2, 1)
    to_image = summing(img, n)
    N = (to_image @ (JwT @ J).reshape(-1, 36)).reshape(n, 6, 6)
    g = to_image @ (JwT @ r[:, :, None])[:, :, 0]
    # scale to unit diagonal: the condition then says whether the geometry determines x
    s = 1.0 / np.sqrt(np.maximum(np.einsum("nii->ni", N), 1e-300))
    Ns = N * s[:, :, None] * s[:, None, :]
    ev = np.linalg.eigvalsh(Ns)
    reg = ev[:, 0] > 1e-12 * np.maximum(ev[:, -1], 1e-300)
    Ns = Ns + lam[:, None, None] * np.eye(6)[None]
    dx = np.zeros((n, 6))
    if reg.any():
        dx[reg] = s[reg] * np.linalg.solve(Ns[reg], (s[reg] * g[reg])[:, :, None])[:, :, 0]
    return dx, reg
