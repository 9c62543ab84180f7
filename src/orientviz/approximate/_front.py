"""A local bundle of the growth front: the images of one wave with their points, the rest held.

A resection uses only the points already intersected; in a strip with 60 % overlap
these lie in the narrow triple-overlap band, and orientations resected from such a
band get worse from image to image (the chain's errors grow geometrically). The
points the new image shares with its oriented neighbours by two rays carry the rest of
the information (their y-parallaxes, as in a relative orientation). :func:`adjust_front`
adjusts the new images of a wave together with every point they see (from all its
oriented rays), the images oriented before being held fixed: a few Gauss-Newton steps
of a small bundle, solved by the Schur complement onto the new images' 6 × 6 blocks
(a dense system of 6 × the wave's images) with the points' 3 × 3 blocks eliminated.

Units and conventions as in ``approximate/_batch.py``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ._batch import linearise, rotate_by, summing

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


def adjust_front(
    cam: I64, pt: I64, xy: F64, c: F64, sigma: F64, R: F64, X0: F64, free: I64, P: F64,
    iterations: int = 3,
) -> tuple[F64, F64, F64, F64]:  # fmt: skip
    """Adjust the images ``free`` and the points ``P`` with all other images held.

    Parameters
    ----------
    cam, pt : ndarray of int, shape (k,)
        Image (index into ``R``/``X0``) and point (index into ``P``) of each ray.
    xy, c, sigma : ndarray, shapes (k, 2), (k,), (k, 2)
        The rays as for ``resect_batch`` (mm).
    R, X0 : ndarray, shapes (n, 3, 3) and (n, 3)
        Orientations of the images the rays refer to (image → object; m).
    free : ndarray of int, shape (b,)
        The images to adjust (indices into ``R``); the others are held.
    P : ndarray, shape (q, 3)
        The points (m), all adjusted; each needs two rays that are not parallel.
    iterations : int
        Gauss-Newton steps.

    Returns
    -------
    R, X0, P : ndarray
        Copies with the adjusted values (the start values if the steps made the weighted
        square sum of all the rays worse).
    sigma0 : ndarray, shape (b,)
        σ̂0 of each free image's rays after the adjustment (a rough one: redundancy
        counted as 2k − 6 for its k rays).
    """
    R, X0, P = R.copy(), X0.copy(), P.copy()
    n, q, b = R.shape[0], P.shape[0], free.size
    slot = -np.ones(n, np.int64)
    slot[free] = np.arange(b)
    wgt = 1.0 / sigma**2
    fr = np.flatnonzero(slot[cam] >= 0)  # rays of free images
    s = slot[cam[fr]]
    to_point = summing(pt, q)
    to_image = summing(s, b)
    to_point_fr = summing(pt[fr], q)
    rows = (6 * s[:, None, None] + np.arange(6)[None, :, None]).repeat(3, 2).ravel()
    cols = (3 * pt[fr, None, None] + np.arange(3)[None, None, :]).repeat(6, 1).ravel()
    held = np.zeros(q, bool)
    start = (R.copy(), X0.copy(), P.copy())
    cost0 = None
    for _ in range(iterations):
        J, r, _ = linearise(cam, xy, c, P[pt], R, X0)  # l − f; ∂f/∂(X0, δ)
        if cost0 is None:
            cost0 = float((r**2 * wgt).sum())
        Jp = -J[:, :, :3]  # ∂f/∂X = −∂f/∂X0
        JpwT = (Jp * wgt[:, :, None]).transpose(0, 2, 1)
        Npp = (to_point @ (JpwT @ Jp).reshape(-1, 9)).reshape(q, 3, 3)
        bp = to_point @ (JpwT @ r[:, :, None])[:, :, 0]
        Jc = J[fr]
        JcwT = (Jc * wgt[fr, :, None]).transpose(0, 2, 1)
        Ncc = (to_image @ (JcwT @ Jc).reshape(-1, 36)).reshape(b, 6, 6)
        bc = to_image @ (JcwT @ r[fr, :, None])[:, :, 0]
        Ncp = JcwT @ Jp[fr]  # (k_free, 6, 3)
        Ninv, det = _inverse3(Npp)
        held |= ~(np.abs(det) > 1e-12 * np.abs(np.einsum("nii->n", Npp)) ** 3)
        Ninv[held] = 0.0  # a point with parallel rays stays where it is
        Y = Ncp @ Ninv[pt[fr]]  # Ncp Npp⁻¹
        Ym = sp.csr_matrix((Y.ravel(), (rows, cols)), shape=(6 * b, 3 * q))
        Wm = sp.csr_matrix((Ncp.ravel(), (rows, cols)), shape=(6 * b, 3 * q))
        S = -(Ym @ Wm.T).toarray()
        i6 = np.arange(6 * b)[:, None]
        S[i6, 6 * (i6 // 6) + np.arange(6)] += Ncc.reshape(6 * b, 6)
        rhs = bc.ravel() - Ym @ bp.ravel()
        try:
            dc = np.linalg.solve(S, rhs).reshape(b, 6)
        except np.linalg.LinAlgError:
            break
        back = to_point_fr @ (Ncp.transpose(0, 2, 1) @ dc[s][:, :, None])[:, :, 0]
        dp = (Ninv @ (bp - back)[:, :, None])[:, :, 0]
        if not (np.isfinite(dc).all() and np.isfinite(dp).all()):
            break
        X0[free] += dc[:, :3]
        R[free] = rotate_by(R[free], dc[:, 3:])
        P += dp
    _, r, _ = linearise(cam, xy, c, P[pt], R, X0, jacobian=False)
    if cost0 is not None and not float((r**2 * wgt).sum()) <= cost0:  # worse: keep the start
        R, X0, P = start
        _, r, _ = linearise(cam, xy, c, P[pt], R, X0, jacobian=False)
    r = r[fr]
    k = np.bincount(s, minlength=b)
    with np.errstate(invalid="ignore", divide="ignore"):
        sigma0 = np.sqrt(np.bincount(s, (r**2 * wgt[fr]).sum(axis=1), b) / np.maximum(2 * k - 6, 1))
    return R, X0, P, sigma0


def _inverse3(A: F64) -> tuple[F64, F64]:
    """Inverses and determinants of a stack of 3 × 3 matrices (adjugate / determinant)."""
    a, b, c = A[:, 0, 0], A[:, 0, 1], A[:, 0, 2]
    d, e, f = A[:, 1, 0], A[:, 1, 1], A[:, 1, 2]
    g, h, i = A[:, 2, 0], A[:, 2, 1], A[:, 2, 2]
    C = np.empty_like(A)
    C[:, 0, 0], C[:, 0, 1], C[:, 0, 2] = e * i - f * h, c * h - b * i, b * f - c * e
    C[:, 1, 0], C[:, 1, 1], C[:, 1, 2] = f * g - d * i, a * i - c * g, c * d - a * f
    C[:, 2, 0], C[:, 2, 1], C[:, 2, 2] = d * h - e * g, b * g - a * h, a * e - b * d
    det = a * C[:, 0, 0] + b * C[:, 1, 0] + c * C[:, 2, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        return C / det[:, None, None], det
