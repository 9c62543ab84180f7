"""The direct linear transformation (DLT): an approximate resection without approximations.

The collinearity equations (:func:`orientviz.camera.project`) with an affine image
frame can be written as a ratio of linear functions of the object point X = (X, Y, Z):

    x = (L1 X + L2 Y + L3 Z + L4) / (L9 X + L10 Y + L11 Z + 1)
    y = (L5 X + L6 Y + L7 Z + L8) / (L9 X + L10 Y + L11 Z + 1)

(Abdel-Aziz and Karara, 1971). Multiplied out, each point gives two equations that are
*linear* in L1…L11, so six or more control points, not all in one plane, determine them
without approximate values (:func:`dlt`). The eleven parameters hold the six elements of
exterior orientation, the interior orientation (c, x0, y0) and two affine parameters of
the image frame (a scale difference of y against x and a shear), see
:func:`dlt_to_orientation`: in homogeneous form

    P = [[L1 L2 L3 L4], [L5 L6 L7 L8], [L9 L10 L11 1]] ∝ K Rᵀ [I | −X0],
    K = [[−c, s, x0], [0, −c (1 + m), y0], [0, 0, 1]],

with R image → object (:mod:`orientviz.rotation`) and orientviz's image frame (x, y, −c).
The DLT minimises an algebraic error, not the image residuals, and ignores the weights:
its result is an approximation, refined by the rigorous resection
(:func:`orientviz.orientation.resection.resection`).

Units: object coordinates m, image coordinates mm; L1…L11 have mixed units (mm/m, mm, 1/m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError, NotDeterminableError
from ..rotation import opk_from_matrix

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class DLTResult:
    """The eleven DLT parameters with their fit.

    Attributes
    ----------
    L : ndarray, shape (11,)
        L1…L11 (mixed units, see the module docstring).
    residuals : ndarray, shape (n, 2)
        Image residuals (projected − observed), mm.
    rms : float
        RMS of the image residuals, mm.
    redundancy : int
        2n − 11.
    """

    L: F64
    residuals: F64
    rms: float
    redundancy: int

    @property
    def P(self) -> F64:
        """The 3×4 projection matrix with P[2, 3] = 1."""
        return np.append(self.L, 1.0).reshape(3, 4)


@dataclass(frozen=True)
class DLTOrientation:
    """Orientation elements contained in a DLT.

    Attributes
    ----------
    X0 : ndarray, shape (3,)
        Projection centre, m.
    R : ndarray, shape (3, 3)
        Rotation image → object.
    angles : ndarray, shape (3,)
        ω, φ, κ in rad (sequence ``sequence``).
    c, x0, y0 : float
        Principal distance and principal point, mm.
    scale_y : float
        Scale difference m of the y axis against x (c_y = c (1 + m)), dimensionless.
    shear : float
        Shear of the image frame: x picks up ``shear`` times y (K[0, 1] / K[1, 1]),
        dimensionless (≈ the non-orthogonality of the axes in rad).
    """

    X0: F64
    R: F64
    angles: F64
    c: float
    x0: float
    y0: float
    scale_y: float
    shear: float


def _check(image_points: ArrayLike, object_points: ArrayLike) -> tuple[F64, F64]:
    xy = np.asarray(image_points, dtype=float)
    X = np.asarray(object_points, dtype=float)
    if xy.ndim != 2 or xy.shape[1] != 2:
        raise InputError(f"expected image points of shape (n, 2), got {xy.shape}")
    if X.ndim != 2 or X.shape[1] != 3:
        raise InputError(f"expected object points of shape (n, 3), got {X.shape}")
    if len(xy) != len(X):
        raise InputError(f"expected as many image as object points, got {len(xy)} and {len(X)}")
    if len(xy) < 6:
        raise InputError(f"the DLT needs at least 6 control points, got {len(xy)}")
    return xy, X


def dlt_design(image_points: ArrayLike, object_points: ArrayLike) -> tuple[F64, F64]:
    """The linear DLT system A L = b (two rows per point, unknowns L1…L11).

    Row of x: (X, Y, Z, 1, 0, 0, 0, 0, −xX, −xY, −xZ), right side x; row of y:
    (0, 0, 0, 0, X, Y, Z, 1, −yX, −yY, −yZ), right side y.

    Returns
    -------
    A : ndarray, shape (2n, 11)
    b : ndarray, shape (2n,)
        x1, y1, x2, y2, … in mm.
    """
    xy = np.asarray(image_points, dtype=float)
    X = np.asarray(object_points, dtype=float)
    n = len(X)
    A = np.zeros((2 * n, 11))
    one = np.ones((n, 1))
    A[0::2, 0:4] = np.hstack([X, one])
    A[1::2, 4:8] = np.hstack([X, one])
    A[0::2, 8:11] = -xy[:, :1] * X
    A[1::2, 8:11] = -xy[:, 1:] * X
    return A, xy.reshape(-1)


def _conditioner(p: F64) -> F64:
    """Similarity that moves points to their centroid and scales the mean distance to √d."""
    d = p.shape[1]
    m = p.mean(axis=0)
    s = np.sqrt(d) / max(float(np.mean(np.linalg.norm(p - m, axis=1))), 1e-300)
    T = np.eye(d + 1)
    T[:d, :d] *= s
    T[:d, d] = -s * m
    return T


def dlt(image_points: ArrayLike, object_points: ArrayLike) -> DLTResult:
    """Estimate the eleven DLT parameters from n ≥ 6 control points (linear, no start values).

    The points are conditioned (centred and scaled, image and object space separately)
    and the homogeneous system is solved by the SVD; the result is transformed back and
    scaled to P[2, 3] = 1.

    Parameters
    ----------
    image_points : array_like, shape (n, 2)
        Observed image coordinates, mm.
    object_points : array_like, shape (n, 3)
        Control points, m; not all in one plane.

    Returns
    -------
    DLTResult

    Raises
    ------
    NotDeterminableError
        All points (nearly) in one plane, or too few independent equations.
    """
    xy, X = _check(image_points, object_points)
    Ti, To = _conditioner(xy), _conditioner(X)
    xh = np.column_stack([xy, np.ones(len(xy))]) @ Ti.T
    Xh = np.column_stack([X, np.ones(len(X))]) @ To.T
    n = len(X)
    M = np.zeros((2 * n, 12))
    M[0::2, 0:4] = Xh
    M[0::2, 8:12] = -xh[:, :1] * Xh
    M[1::2, 4:8] = Xh
    M[1::2, 8:12] = -xh[:, 1:2] * Xh
    _, sv, Vt = np.linalg.svd(M, full_matrices=False)
    planar = np.linalg.svd(X - X.mean(axis=0), compute_uv=False)
    if sv.size < 12 or sv[-2] < 1e-9 * sv[0] or planar[2] < 1e-6 * planar[0]:
        raise NotDeterminableError(
            "the control points do not determine a DLT (all in one plane, or fewer than "
            "six in general position)",
            parameters=[f"L{k}" for k in range(1, 12)],
            defect=1,
        )
    Pn = Vt[-1].reshape(3, 4)
    P = np.linalg.inv(Ti) @ Pn @ To
    P = P / P[2, 3]
    L = P.reshape(-1)[:11]
    res = dlt_project(L, X) - xy
    return DLTResult(L, res, float(np.sqrt(np.mean(res**2))), 2 * n - 11)


def dlt_project(L: ArrayLike, object_points: ArrayLike) -> F64:
    """Image coordinates (n, 2) in mm of object points (n, 3) in m by the DLT ``L`` (11,)."""
    P = np.append(np.asarray(L, dtype=float), 1.0).reshape(3, 4)
    X = np.asarray(object_points, dtype=float)
    h = np.column_stack([X, np.ones(len(X))]) @ P.T
    return h[:, :2] / h[:, 2:]


def dlt_to_orientation(L: ArrayLike, sequence: str = "opk") -> DLTOrientation:
    """Split a DLT into exterior orientation, interior orientation and the affine terms.

    X0 = −M⁻¹ p4 (M the left 3×3 of P, p4 its last column); M ∝ K Rᵀ is split by an RQ
    decomposition with the signs of orientviz's image frame (K[0, 0], K[1, 1] < 0).

    Parameters
    ----------
    L : array_like, shape (11,)
    sequence : {"opk", "pok"}
        Rotation sequence of the returned angles.

    Returns
    -------
    DLTOrientation
    """
    from scipy.linalg import rq

    P = np.append(np.asarray(L, dtype=float), 1.0).reshape(3, 4)
    M, p4 = P[:, :3], P[:, 3]
    X0 = -np.linalg.solve(M, p4)
    if np.linalg.det(M) < 0:  # M = λ K Rᵀ with det K > 0 and det R = 1: make λ > 0
        M = -M
    K, Q = rq(M)
    S = np.diag(np.sign(np.diag(K)) * np.array([-1.0, -1.0, 1.0]))
    K, Rt = K @ S, S @ Q
    K = K / K[2, 2]
    R = Rt.T
    c = -K[0, 0]
    return DLTOrientation(
        X0=X0,
        R=R,
        angles=np.asarray(opk_from_matrix(R, sequence), dtype=float),
        c=float(c),
        x0=float(K[0, 2]),
        y0=float(K[1, 2]),
        scale_y=float(K[1, 1] / K[0, 0] - 1.0),
        shear=float(K[0, 1] / K[1, 1]),
    )
