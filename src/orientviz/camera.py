"""The frame camera: interior orientation and the collinearity equations.

Image coordinates are in **millimetres** in the fiducial (image) frame: x along the
flight direction, y to its left, z towards the viewer; the projection centre lies at
(x0, y0, +c) above the image plane, so the image plane is at z = −c relative to it
(principal distance c > 0). With R from :mod:`orientviz.rotation` (image → object)::

    (u, v, w)ᵀ = Rᵀ · (X − X0)
    x = x0 − c · u / w
    y = y0 − c · v / w

For a vertical photograph (R = I) over terrain below the camera, w < 0, so a point
ahead in +X images at +x, as on a positive (diapositive).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .rotation import matrix_derivatives, matrix_from_opk

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class FrameCamera:
    """Interior orientation of a metric frame camera.

    Parameters
    ----------
    c : float
        Principal distance in mm (> 0), e.g. 152.7 for a wide-angle camera.
    x0, y0 : float
        Principal point in mm, in the fiducial frame.
    format_mm : tuple of float
        Image format (width along x, height along y) in mm, e.g. (230, 230).
    name : str
        Identifier.
    """

    c: float
    x0: float = 0.0
    y0: float = 0.0
    format_mm: tuple[float, float] = (230.0, 230.0)
    name: str = "camera"
    extra: dict = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        if not np.isfinite(self.c) or self.c <= 0:
            raise ValueError(f"expected a principal distance c > 0 mm, got {self.c}")
        for label, v in (("x0", self.x0), ("y0", self.y0)):
            if not np.isfinite(v):
                raise ValueError(f"expected a finite {label} in mm, got {v}")

    def corners(self) -> F64:
        """Image corners (4, 2) in mm, counter-clockwise from (+x, +y)."""
        w, h = self.format_mm[0] / 2, self.format_mm[1] / 2
        return np.array([[w, h], [-w, h], [-w, -h], [w, -h]], dtype=float)


def image_vectors(points: ArrayLike, X0: ArrayLike, R: ArrayLike) -> F64:
    """Object vectors turned into the image frame, (u, v, w) = Rᵀ (X − X0).

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Object points in m.
    X0 : array_like, shape (3,) or (n, 3)
        Projection centre(s) in m.
    R : array_like, shape (3, 3) or (n, 3, 3)
        Rotation(s) image → object.

    Returns
    -------
    ndarray, shape (n, 3)
    """
    d = np.asarray(points, dtype=float) - np.asarray(X0, dtype=float)
    R = np.asarray(R, dtype=float)
    if R.ndim == 2:
        return d @ R
    return np.einsum("nji,nj->ni", R, d)


def project(
    points: ArrayLike,
    X0: ArrayLike,
    R: ArrayLike,
    c: ArrayLike,
    x0: ArrayLike = 0.0,
    y0: ArrayLike = 0.0,
) -> F64:
    """Collinearity equations: image coordinates (mm) of object points.

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Object points in m.
    X0 : array_like, shape (3,) or (n, 3)
        Projection centre(s) in m.
    R : array_like, shape (3, 3) or (n, 3, 3)
        Rotation(s) image → object (see :mod:`orientviz.rotation`).
    c, x0, y0 : float or array_like, shape (n,)
        Principal distance and principal point in mm.

    Returns
    -------
    ndarray, shape (n, 2)
        Image coordinates x, y in mm.
    """
    uvw = image_vectors(points, X0, R)
    c = np.asarray(c, dtype=float)
    out = np.empty(uvw.shape[:-1] + (2,))
    out[..., 0] = np.asarray(x0, dtype=float) - c * uvw[..., 0] / uvw[..., 2]
    out[..., 1] = np.asarray(y0, dtype=float) - c * uvw[..., 1] / uvw[..., 2]
    return out


def collinearity_jacobian(
    points: ArrayLike,
    X0: ArrayLike,
    angles: ArrayLike,
    c: ArrayLike,
    x0: ArrayLike = 0.0,
    y0: ArrayLike = 0.0,
    sequence: str = "opk",
) -> tuple[F64, F64, F64, F64]:
    """Image coordinates and their partial derivatives, vectorised over n rays.

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Object points in m.
    X0 : array_like, shape (n, 3) or (3,)
        Projection centres in m.
    angles : array_like, shape (n, 3) or (3,)
        ω, φ, κ in radians.
    c, x0, y0 : float or array_like, shape (n,)
        Interior orientation in mm.
    sequence : {"opk", "pok"}
        Rotation sequence of ``angles``.

    Returns
    -------
    xy : ndarray, shape (n, 2)
        Image coordinates in mm.
    J_exterior : ndarray, shape (n, 2, 6)
        ∂(x, y)/∂(X0, Y0, Z0, ω, φ, κ) in mm/m and mm/rad.
    J_point : ndarray, shape (n, 2, 3)
        ∂(x, y)/∂(X, Y, Z) in mm/m.
    J_interior : ndarray, shape (n, 2, 3)
        ∂(x, y)/∂(x0, y0, c), dimensionless.
    """
    P = np.atleast_2d(np.asarray(points, dtype=float))
    n = P.shape[0]
    X0 = np.broadcast_to(np.asarray(X0, dtype=float), (n, 3))
    ang = np.broadcast_to(np.asarray(angles, dtype=float), (n, 3))
    c = np.broadcast_to(np.asarray(c, dtype=float), (n,))
    R = matrix_from_opk(ang[:, 0], ang[:, 1], ang[:, 2], sequence)
    dR = np.stack(matrix_derivatives(ang[:, 0], ang[:, 1], ang[:, 2], sequence), 1)
    dxy, J_point, J_angles, uvw = collinearity_partials(P - X0, R, dR, c)
    xy = np.empty((n, 2))
    xy[:, 0] = np.broadcast_to(np.asarray(x0, dtype=float), (n,)) + dxy[:, 0]
    xy[:, 1] = np.broadcast_to(np.asarray(y0, dtype=float), (n,)) + dxy[:, 1]
    J_ext = np.empty((n, 2, 6))
    J_ext[:, :, :3] = -J_point
    J_ext[:, :, 3:] = J_angles
    J_int = np.zeros((n, 2, 3))
    J_int[:, 0, 0] = 1.0
    J_int[:, 1, 1] = 1.0
    J_int[:, 0, 2] = -uvw[:, 0] / uvw[:, 2]
    J_int[:, 1, 2] = -uvw[:, 1] / uvw[:, 2]
    return xy, J_ext, J_point, J_int


def collinearity_partials(d: F64, R: F64, dR: F64, c: F64) -> tuple[F64, F64, F64, F64]:
    """The derivative chain of the collinearity equations, vectorised over n rays.

    Used by :func:`collinearity_jacobian`; the bundle's kernel
    (:mod:`orientviz.bundle.model._kernel`) computes the same chain arranged per image.

    Parameters
    ----------
    d : ndarray, shape (n, 3)
        X − X0 in m.
    R : ndarray, shape (n, 3, 3)
        Rotations image → object.
    dR : ndarray, shape (n, 3, 3, 3)
        ∂R/∂ω, ∂R/∂φ, ∂R/∂κ stacked on axis 1 (per radian).
    c : ndarray, shape (n,)
        Principal distances in mm.

    Returns
    -------
    dxy : ndarray, shape (n, 2)
        −c·(u, v)/w: the image coordinates relative to the principal point, mm.
    J_point : ndarray, shape (n, 2, 3)
        ∂(x, y)/∂(X, Y, Z) in mm/m (∂/∂X0 is its negative).
    J_angles : ndarray, shape (n, 2, 3)
        ∂(x, y)/∂(ω, φ, κ) in mm/rad.
    uvw : ndarray, shape (n, 3)
        Rᵀ d.

    Notes
    -----
    With a = −c/w and b = c·(u, v)/w²: ∂(x, y)/∂(u, v, w) = [[a, 0, b_u], [0, a, b_v]],
    ∂(u, v, w)/∂X = Rᵀ and ∂(u, v, w)/∂θ = (∂R/∂θ)ᵀ d.
    """
    uvw = np.einsum("nji,nj->ni", R, d)
    u, v, w = uvw[:, 0], uvw[:, 1], uvw[:, 2]
    a = -c / w
    n = d.shape[0]
    dxy = np.empty((n, 2))
    dxy[:, 0] = a * u
    dxy[:, 1] = a * v
    bu = -a * u / w  # c u / w²
    bv = -a * v / w
    # rows of Rᵀ are the columns of R
    Jp = np.empty((n, 2, 3))
    Jp[:, 0] = a[:, None] * R[:, :, 0] + bu[:, None] * R[:, :, 2]
    Jp[:, 1] = a[:, None] * R[:, :, 1] + bv[:, None] * R[:, :, 2]
    duvw = np.einsum("nkji,nj->nki", dR, d)  # (n, 3 angles, 3 components)
    Ja = np.empty((n, 2, 3))
    Ja[:, 0] = a[:, None] * duvw[:, :, 0] + bu[:, None] * duvw[:, :, 2]
    Ja[:, 1] = a[:, None] * duvw[:, :, 1] + bv[:, None] * duvw[:, :, 2]
    return dxy, Jp, Ja, uvw


def rays(
    xy: ArrayLike, R: ArrayLike, c: ArrayLike, x0: ArrayLike = 0.0, y0: ArrayLike = 0.0
) -> F64:
    """Object-frame ray directions R·(x − x0, y − y0, −c) (not normalised), shape (n, 3).

    Parameters
    ----------
    xy : array_like, shape (n, 2)
        Image coordinates in mm.
    R : array_like, shape (3, 3) or (n, 3, 3)
        Rotation(s) image → object.
    c, x0, y0 : float or array_like
        Interior orientation in mm.
    """
    xy = np.atleast_2d(np.asarray(xy, dtype=float))
    vec = np.empty((xy.shape[0], 3))
    vec[:, 0] = xy[:, 0] - x0
    vec[:, 1] = xy[:, 1] - y0
    vec[:, 2] = -np.broadcast_to(np.asarray(c, dtype=float), (xy.shape[0],))
    R = np.asarray(R, dtype=float)
    if R.ndim == 2:
        return vec @ R.T
    return np.einsum("nij,nj->ni", R, vec)
