"""Vectorised collinearity kernel of the bundle adjustment.

The same equations as :func:`orientviz.camera.collinearity_jacobian` (image plane at
z = −c, R image → object, ``x = x0 − c·u/w``, ``y = y0 − c·v/w`` with
(u, v, w) = Rᵀ (X − X0)) and the same derivative chain
(:func:`orientviz.camera.collinearity_partials`), but the rotation matrices and their
derivatives are computed once per *image* and gathered per observation, which is what
a block with 100 000 observations and 2 000 images needs. Rotation sequence ``"opk"`` (R = R_ω R_φ R_κ) or
``"pok"`` (R = R_φ R_ω R_κ), see :mod:`orientviz.rotation`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..camera import collinearity_partials, project
from ..rotation import matrix_derivatives, matrix_from_opk
from ._local_rotation import local_derivatives

F64 = NDArray[np.float64]


def project_block(
    X0: F64,
    angles: F64,
    c: F64,
    x0: F64,
    y0: F64,
    obs_image: NDArray[np.int64],
    xyz: F64,
    sequence: str = "opk",
) -> F64:
    """Image coordinates (n, 2) in mm of observation rays.

    Parameters
    ----------
    X0 : ndarray, shape (m, 3)
        Projection centres in m.
    angles : ndarray, shape (m, 3)
        ω, φ, κ in rad (sequence ``sequence``).
    c, x0, y0 : ndarray, shape (m,)
        Interior orientation per image in mm.
    obs_image : ndarray of int, shape (n,)
        Image of each observation.
    xyz : ndarray, shape (n, 3)
        Object point of each observation in m.
    sequence : {"opk", "pok"}
    """
    R = matrix_from_opk(angles[:, 0], angles[:, 1], angles[:, 2], sequence)
    oi = obs_image
    return project(xyz, X0[oi], R[oi], c[oi], x0[oi], y0[oi])


def collinearity_block(
    X0: F64,
    angles: F64,
    c: F64,
    x0: F64,
    y0: F64,
    obs_image: NDArray[np.int64],
    xyz: F64,
    sequence: str = "opk",
    local: bool = False,
) -> tuple[F64, F64, F64]:
    """Image coordinates and Jacobians of all observations of a block.

    Parameters are those of :func:`project_block`; ``local``: the last three columns of
    J_exterior are derivatives by a small rotation δ of the image frame,
    R(δ) = R·exp([δ]×), instead of by ω, φ, κ (no gimbal lock; see
    :mod:`orientviz.bundle._local_rotation`).

    Returns
    -------
    xy : ndarray, shape (n, 2)
        Image coordinates in mm.
    J_exterior : ndarray, shape (n, 2, 6)
        ∂(x, y)/∂(X0, Y0, Z0, ω, φ, κ) in mm/m and mm/rad.
    J_point : ndarray, shape (n, 2, 3)
        ∂(x, y)/∂(X, Y, Z) in mm/m.
    """
    R = matrix_from_opk(angles[:, 0], angles[:, 1], angles[:, 2], sequence)
    if local:
        dR = local_derivatives(R)
    else:
        dR = np.stack(matrix_derivatives(angles[:, 0], angles[:, 1], angles[:, 2], sequence), 1)
    oi = obs_image
    dxy, Jp, Ja, _ = collinearity_partials(xyz - X0[oi], R[oi], dR[oi], c[oi])
    xy = np.empty_like(dxy)
    xy[:, 0] = x0[oi] + dxy[:, 0]
    xy[:, 1] = y0[oi] + dxy[:, 1]
    Je = np.empty((oi.shape[0], 2, 6))
    Je[:, :, :3] = -Jp
    Je[:, :, 3:] = Ja
    return xy, Je, Jp


def normalised_block(
    X0: F64,
    angles: F64,
    obs_image: NDArray[np.int64],
    xyz: F64,
    sequence: str = "opk",
    jac: bool = True,
) -> tuple[F64, F64 | None, F64 | None]:
    """Normalised image points n = −(u, v)/w of rays and their Jacobians.

    The pinhole part of a camera model that applies c, the principal point and the lens
    itself (:mod:`orientviz.bundle._lens`): ``project_block`` with c = 1, x0 = y0 = 0.

    Returns
    -------
    n : ndarray, shape (n, 2)
        Normalised image points (unitless).
    J_exterior : ndarray, shape (n, 2, 6) or None
        ∂n/∂(X0, Y0, Z0, ω, φ, κ) in 1/m and 1/rad (None without ``jac``).
    J_point : ndarray, shape (n, 2, 3) or None
        ∂n/∂(X, Y, Z) in 1/m.
    """
    one = np.ones(X0.shape[0])
    zero = np.zeros(X0.shape[0])
    if not jac:
        return project_block(X0, angles, one, zero, zero, obs_image, xyz, sequence), None, None
    return collinearity_block(X0, angles, one, zero, zero, obs_image, xyz, sequence)
