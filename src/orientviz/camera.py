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
    dR = matrix_derivatives(ang[:, 0], ang[:, 1], ang[:, 2], sequence)
    d = P - X0
    uvw = np.einsum("nji,nj->ni", R, d)
    u, v, w = uvw[:, 0], uvw[:, 1], uvw[:, 2]
    xy = np.empty((n, 2))
    xy[:, 0] = np.broadcast_to(np.asarray(x0, dtype=float), (n,)) - c * u / w
    xy[:, 1] = np.broadcast_to(np.asarray(y0, dtype=float), (n,)) - c * v / w
    # d(x, y) / d(u, v, w)
    dxy_duvw = np.zeros((n, 2, 3))
    dxy_duvw[:, 0, 0] = -c / w
    dxy_duvw[:, 0, 2] = c * u / w**2
    dxy_duvw[:, 1, 1] = -c / w
    dxy_duvw[:, 1, 2] = c * v / w**2
    Rt = np.swapaxes(R, 1, 2)
    J_point = dxy_duvw @ Rt
    J_ext = np.empty((n, 2, 6))
    J_ext[:, :, :3] = -J_point
    for k in range(3):
        duvw = np.einsum("nji,nj->ni", dR[k], d)
        J_ext[:, :, 3 + k] = np.einsum("nab,nb->na", dxy_duvw, duvw)
    J_int = np.zeros((n, 2, 3))
    J_int[:, 0, 0] = 1.0
    J_int[:, 1, 1] = 1.0
    J_int[:, 0, 2] = -u / w
    J_int[:, 1, 2] = -v / w
    return xy, J_ext, J_point, J_int


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
