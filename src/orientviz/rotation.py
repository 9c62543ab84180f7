"""Rotation matrices of photogrammetry: the ω-φ-κ and φ-ω-κ sequences.

Convention (used everywhere in orientviz)
-----------------------------------------
A rotation matrix ``R`` turns vectors of the *image* (camera) frame into the *object*
frame::

    X - X0 = λ · R · (x - x0, y - y0, -c)ᵀ

and is composed of three elementary, right-handed (counter-clockwise seen from the
positive axis) rotations about the object axes X (ω), Y (φ) and Z (κ):

* ``"opk"`` (default, the ω-φ-κ system of analytical photogrammetry):
  ``R = R_ω · R_φ · R_κ`` — ω is the primary axis, fixed in object space.
* ``"pok"`` (the φ-ω-κ system of Wild and most analogue plotters):
  ``R = R_φ · R_ω · R_κ`` — φ is the primary axis.

with ::

    R_ω = [[1, 0, 0], [0, cos ω, −sin ω], [0, sin ω, cos ω]]
    R_φ = [[cos φ, 0, sin φ], [0, 1, 0], [−sin φ, 0, cos φ]]
    R_κ = [[cos κ, −sin κ, 0], [sin κ, cos κ, 0], [0, 0, 1]]

All angles are radians. Every function is vectorised: angles of shape ``(...)`` give
matrices of shape ``(..., 3, 3)``.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

Sequence = Literal["opk", "pok"]

#: Rotation sequences by name → order of the axes, primary first (0 = X/ω, 1 = Y/φ, 2 = Z/κ).
SEQUENCES: dict[str, tuple[int, int, int]] = {"opk": (0, 1, 2), "pok": (1, 0, 2)}
#: Aliases accepted on input.
_ALIASES = {"omega-phi-kappa": "opk", "phi-omega-kappa": "pok", "ω-φ-κ": "opk", "φ-ω-κ": "pok"}

#: Below this abs(cos) of the secondary angle the conversion to angles treats the
#: matrix as gimbal-locked and sets κ = 0.
GIMBAL_TOLERANCE: float = 1e-9


def check_sequence(sequence: str) -> str:
    """Return the canonical sequence name (``"opk"`` or ``"pok"``) or raise ``ValueError``."""
    name = _ALIASES.get(sequence, sequence)
    if name not in SEQUENCES:
        raise ValueError(
            "expected a rotation sequence 'opk' (omega-phi-kappa) or 'pok' (phi-omega-kappa), "
            f"got {sequence!r}"
        )
    return name


def elementary(axis: int, angle: ArrayLike) -> NDArray[np.float64]:
    """Elementary rotation about object axis ``axis`` (0 = X, 1 = Y, 2 = Z).

    Parameters
    ----------
    axis : {0, 1, 2}
        Rotation axis.
    angle : float or array_like, shape (...)
        Rotation angle in radians, right-handed.

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    a = np.asarray(angle, dtype=float)
    c, s = np.cos(a), np.sin(a)
    out = np.zeros(a.shape + (3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    out[..., axis, axis] = 1.0
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., i, j] = -s
    out[..., j, i] = s
    return out


def _elementary_derivative(axis: int, angle: NDArray[np.float64]) -> NDArray[np.float64]:
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros(angle.shape + (3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    out[..., i, i] = -s
    out[..., j, j] = -s
    out[..., i, j] = -c
    out[..., j, i] = c
    return out


def _factors(omega: ArrayLike, phi: ArrayLike, kappa: ArrayLike, sequence: str):
    angles = np.broadcast_arrays(
        np.asarray(omega, dtype=float), np.asarray(phi, dtype=float), np.asarray(kappa, dtype=float)
    )
    order = SEQUENCES[check_sequence(sequence)]
    return angles, order


def matrix_from_opk(
    omega: ArrayLike, phi: ArrayLike, kappa: ArrayLike, sequence: str = "opk"
) -> NDArray[np.float64]:
    """Rotation matrix from the angles ω, φ, κ.

    Parameters
    ----------
    omega, phi, kappa : float or array_like, shape (...)
        Rotations about X, Y and Z in radians.
    sequence : {"opk", "pok"}, default "opk"
        ``"opk"``: R = R_ω R_φ R_κ; ``"pok"``: R = R_φ R_ω R_κ (see module docstring).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        Matrix turning image-frame vectors into the object frame.
    """
    angles, order = _factors(omega, phi, kappa, sequence)
    mats = [elementary(ax, angles[ax]) for ax in order]
    return mats[0] @ mats[1] @ mats[2]


def matrix_derivatives(
    omega: ArrayLike, phi: ArrayLike, kappa: ArrayLike, sequence: str = "opk"
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Partial derivatives ∂R/∂ω, ∂R/∂φ, ∂R/∂κ of :func:`matrix_from_opk`.

    Parameters
    ----------
    omega, phi, kappa : float or array_like, shape (...)
        Angles in radians.
    sequence : {"opk", "pok"}, default "opk"
        Rotation sequence.

    Returns
    -------
    tuple of three ndarrays, each shape (..., 3, 3)
        Derivatives per radian, in the order ω, φ, κ.
    """
    angles, order = _factors(omega, phi, kappa, sequence)
    mats = [elementary(ax, angles[ax]) for ax in order]
    derivs = {}
    for pos, ax in enumerate(order):
        f = list(mats)
        f[pos] = _elementary_derivative(ax, angles[ax])
        derivs[ax] = f[0] @ f[1] @ f[2]
    return derivs[0], derivs[1], derivs[2]


def opk_from_matrix(
    R: ArrayLike, sequence: str = "opk"
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Angles ω, φ, κ (radians) of a rotation matrix; inverse of :func:`matrix_from_opk`.

    The secondary angle (φ for ``"opk"``, ω for ``"pok"``) is returned in [−π/2, π/2],
    the others in (−π, π]. In gimbal lock (secondary angle at ±π/2, where only the sum
    or difference of the other two is defined) κ is set to 0 and the primary angle
    takes the whole rotation.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrix (image → object).
    sequence : {"opk", "pok"}, default "opk"

    Returns
    -------
    omega, phi, kappa : ndarray, shape (...)
    """
    R = check_rotation_matrix(R)
    seq = check_sequence(sequence)
    if seq == "opk":
        sec = np.arcsin(np.clip(R[..., 0, 2], -1.0, 1.0))
        cos_sec = np.sqrt(R[..., 0, 0] ** 2 + R[..., 0, 1] ** 2)
        locked = cos_sec < GIMBAL_TOLERANCE
        prim = np.where(
            locked, np.arctan2(R[..., 2, 1], R[..., 1, 1]), np.arctan2(-R[..., 1, 2], R[..., 2, 2])
        )
        kap = np.where(locked, 0.0, np.arctan2(-R[..., 0, 1], R[..., 0, 0]))
        return prim, sec, kap
    # pok: R = R_phi R_omega R_kappa
    sec = np.arcsin(np.clip(-R[..., 1, 2], -1.0, 1.0))
    cos_sec = np.sqrt(R[..., 1, 0] ** 2 + R[..., 1, 1] ** 2)
    locked = cos_sec < GIMBAL_TOLERANCE
    prim = np.where(
        locked, np.arctan2(-R[..., 2, 0], R[..., 0, 0]), np.arctan2(R[..., 0, 2], R[..., 2, 2])
    )
    kap = np.where(locked, 0.0, np.arctan2(R[..., 1, 0], R[..., 1, 1]))
    return sec, prim, kap


def convert_sequence(
    omega: ArrayLike, phi: ArrayLike, kappa: ArrayLike, from_sequence: str, to_sequence: str
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Re-express a rotation given in one sequence as angles of another (radians)."""
    return opk_from_matrix(matrix_from_opk(omega, phi, kappa, from_sequence), to_sequence)


def check_rotation_matrix(R: ArrayLike, atol: float = 1e-6) -> NDArray[np.float64]:
    """Return ``R`` as a float array of shape (..., 3, 3) or raise ``ValueError``.

    Checks the shape, finiteness, orthonormality (to ``atol``) and det = +1.
    """
    R = np.asarray(R, dtype=float)
    if R.shape[-2:] != (3, 3):
        raise ValueError(f"expected a rotation matrix of shape (..., 3, 3), got {R.shape}")
    if not np.all(np.isfinite(R)):
        raise ValueError("expected a finite rotation matrix, got NaN or inf")
    err = np.abs(np.swapaxes(R, -1, -2) @ R - np.eye(3)).max() if R.size else 0.0
    if err > atol:
        raise ValueError(f"expected an orthonormal matrix, got RᵀR − I up to {err:.2e}")
    if R.size and np.any(np.linalg.det(R) < 0):
        raise ValueError("expected a proper rotation (det R = +1), got a reflection")
    return R


def skew(v: ArrayLike) -> NDArray[np.float64]:
    """Cross-product matrix [v]ₓ with [v]ₓ·u = v × u, shape (..., 3, 3)."""
    v = np.asarray(v, dtype=float)
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def matrix_from_rotvec(rotvec: ArrayLike) -> NDArray[np.float64]:
    """Rotation matrix from a rotation vector (axis × angle in radians), Rodrigues' formula.

    Parameters
    ----------
    rotvec : array_like, shape (..., 3)

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    v = np.asarray(rotvec, dtype=float)
    theta = np.linalg.norm(v, axis=-1)[..., None, None]
    K = skew(v)
    small = theta < 1e-8
    safe = np.where(small, 1.0, theta)
    a = np.where(small, 1.0 - theta**2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - theta**2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    return np.eye(3) + a * K + b * (K @ K)


def rotvec_from_matrix(R: ArrayLike) -> NDArray[np.float64]:
    """Rotation vector of a rotation matrix, robust near θ = π (via quaternions)."""
    from scipy.spatial.transform import Rotation

    R = check_rotation_matrix(R)
    return Rotation.from_matrix(R.reshape(-1, 3, 3)).as_rotvec().reshape(R.shape[:-2] + (3,))
