"""Vectorised collinearity kernel of the bundle adjustment.

The same equations as :func:`orientviz.camera.collinearity_jacobian` (image plane at
z = −c, R image → object, ``x = x0 − c·u/w``, ``y = y0 − c·v/w`` with
(u, v, w) = Rᵀ (X − X0)), but the rotation matrices and their derivatives are computed
once per *image* and gathered per observation, which is what a block with 100 000
observations and 2 000 images needs. Rotation sequence ``"opk"`` (R = R_ω R_φ R_κ) or
``"pok"`` (R = R_φ R_ω R_κ), see :mod:`orientviz.rotation`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..rotation import matrix_derivatives, matrix_from_opk

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
    d = xyz - X0[obs_image]
    uvw = np.einsum("nji,nj->ni", R[obs_image], d)
    out = np.empty((d.shape[0], 2))
    cw = -c[obs_image] / uvw[:, 2]
    out[:, 0] = x0[obs_image] + cw * uvw[:, 0]
    out[:, 1] = y0[obs_image] + cw * uvw[:, 1]
    return out


def collinearity_block(
    X0: F64,
    angles: F64,
    c: F64,
    x0: F64,
    y0: F64,
    obs_image: NDArray[np.int64],
    xyz: F64,
    sequence: str = "opk",
) -> tuple[F64, F64, F64]:
    """Image coordinates and Jacobians of all observations of a block.

    Parameters are those of :func:`project_block`.

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
    dR = np.stack(matrix_derivatives(angles[:, 0], angles[:, 1], angles[:, 2], sequence), 1)
    n = obs_image.shape[0]
    d = xyz - X0[obs_image]
    Ri = R[obs_image]
    uvw = np.einsum("nji,nj->ni", Ri, d)
    u, v, w = uvw[:, 0], uvw[:, 1], uvw[:, 2]
    ci = c[obs_image]
    a = -ci / w
    xy = np.empty((n, 2))
    xy[:, 0] = x0[obs_image] + a * u
    xy[:, 1] = y0[obs_image] + a * v
    bu = -a * u / w  # c u / w²
    bv = -a * v / w
    # ∂(x, y)/∂X = a·R[:, :, 0|1] + b·R[:, :, 2]   (columns of R = rows of Rᵀ)
    Jp = np.empty((n, 2, 3))
    Jp[:, 0] = a[:, None] * Ri[:, :, 0] + bu[:, None] * Ri[:, :, 2]
    Jp[:, 1] = a[:, None] * Ri[:, :, 1] + bv[:, None] * Ri[:, :, 2]
    Je = np.empty((n, 2, 6))
    Je[:, :, :3] = -Jp
    # ∂uvw/∂θ_k = dR_kᵀ d  → (n, 3 angles, 3 components)
    duvw = np.einsum("nkji,nj->nki", dR[obs_image], d)
    Je[:, 0, 3:] = a[:, None] * duvw[:, :, 0] + bu[:, None] * duvw[:, :, 2]
    Je[:, 1, 3:] = a[:, None] * duvw[:, :, 1] + bv[:, None] * duvw[:, :, 2]
    return xy, Je, Jp
