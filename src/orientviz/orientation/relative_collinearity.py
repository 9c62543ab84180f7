"""Relative orientation by the collinearity equations (the textbook method).

The dependent pair of :mod:`orientviz.orientation.relative` (left bundle fixed at the
origin with R1 = I, right projection centre O2 = (b, by, bz), right rotation R2 from
ω, φ, κ), estimated the way analytical-photogrammetry textbooks do it: every image
coordinate of both images is an observation, the unknowns are the five elements *and*
the model coordinates of every point, and the collinearity equations
(:mod:`orientviz.camera`) are adjusted by Gauss-Newton. This is the bundle adjustment of
two images with the datum of a dependent pair (seven parameters held: the left bundle's
six and bx).

Kovarik's estimator (``method="parallax"``) adjusts one rigorous y-parallax per point
instead; both give the same elements for error-free data and differ in the second
order of the measuring errors (different weighting of the same information). The
coplanarity formulation (one triple product B·(r1×r2) = 0 per point, its σ propagated
from the image coordinates; ``method="coplanarity"``,
:mod:`orientviz.orientation.relative_coplanarity`) gives this estimate up to terms of
the second order in the errors.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..adjust.engine import gauss_newton
from ..adjust.result import Adjustment
from ..rotation import matrix_derivatives, matrix_from_opk

F64 = NDArray[np.float64]


def _project(d: F64, c: float) -> tuple[F64, F64]:
    """Image coordinates of direction vectors d (n, 3) and ∂(x, y)/∂d (n, 2, 3)."""
    u, v, w = d[:, 0], d[:, 1], d[:, 2]
    xy = np.column_stack([-c * u / w, -c * v / w])
    J = np.zeros((d.shape[0], 2, 3))
    J[:, 0, 0] = -c / w
    J[:, 0, 2] = c * u / w**2
    J[:, 1, 1] = -c / w
    J[:, 1, 2] = c * v / w**2
    return xy, J


def collinearity_pair(
    xy1: F64,
    xy2: F64,
    c: float,
    b: float,
    start: F64,
    points: F64,
    sigma: float,
    sequence: str,
    labels: list[str] | None,
    max_iter: int,
) -> tuple[Adjustment, F64]:
    """Adjust the five elements and the model points from all image coordinates.

    Parameters
    ----------
    xy1, xy2 : ndarray, shape (n, 2)
        Image coordinates (mm), reduced to the principal point.
    c : float
        Principal distance (mm).
    b : float
        Base component bx (model units, held).
    start : ndarray, shape (5,)
        Start values of by, bz (model units), ω, φ, κ (rad).
    points : ndarray, shape (n, 3)
        Start values of the model points (model units).
    sigma : float
        A-priori σ of an image coordinate (mm).
    sequence : {"opk", "pok"}
    labels : list of str, optional
        Point labels (observations are labelled ``L/<id>/x`` …).
    max_iter : int

    Returns
    -------
    Adjustment, ndarray (n, 3)
        The adjustment of the 5 + 3n unknowns (elements first) and the model points.
    """
    n = xy1.shape[0]
    ids = labels or [str(i + 1) for i in range(n)]
    obs = np.concatenate([xy1.reshape(-1), xy2.reshape(-1)])

    def equations(x: F64) -> tuple[F64, F64]:
        by, bz, om, ph, ka = x[:5]
        P = x[5:].reshape(n, 3)
        R2 = matrix_from_opk(om, ph, ka, sequence)
        dR = matrix_derivatives(om, ph, ka, sequence)
        f1, J1 = _project(P, c)  # left: R1 = I, O1 = 0
        D = P - np.array([b, by, bz])
        f2, J2 = _project(D @ R2, c)  # R2ᵀ (P − O2) per row
        A = np.zeros((4 * n, 5 + 3 * n))
        for k in range(n):  # the left image's rows: only the point
            A[2 * k : 2 * k + 2, 5 + 3 * k : 8 + 3 * k] = J1[k]
        right = 2 * n
        dP = J2 @ R2.T  # ∂(x, y)/∂P = J2 R2ᵀ
        for k in range(n):
            r = right + 2 * k
            A[r : r + 2, 5 + 3 * k : 8 + 3 * k] = dP[k]
            A[r : r + 2, 0] = -dP[k][:, 1]  # by
            A[r : r + 2, 1] = -dP[k][:, 2]  # bz
            for j in range(3):
                A[r : r + 2, 2 + j] = J2[k] @ (dR[j].T @ D[k])
        return np.concatenate([f1.reshape(-1), f2.reshape(-1)]), A

    names = ["by", "bz", "omega", "phi", "kappa"] + [
        f"{p}.{a}" for p in ids for a in ("X", "Y", "Z")
    ]
    obs_labels = [f"{side}/{p}/{a}" for side in ("L", "R") for p in ids for a in "xy"]
    x0 = np.concatenate([np.asarray(start, float), np.asarray(points, float).reshape(-1)])
    res = gauss_newton(
        equations,
        x0,
        obs,
        sigma,
        names=names,
        obs_labels=obs_labels,
        max_iter=max_iter,
        tol=1e-8,
        context="relative orientation (collinearity)",
    )
    return res, res.x[5:].reshape(n, 3)
