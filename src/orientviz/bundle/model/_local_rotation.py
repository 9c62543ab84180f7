"""Rotation steps in the image frame while the approximations are poor.

The bundle's unknowns are ω, φ, κ. Near φ = ±90° (``"opk"``; ω = ±90° for ``"pok"``)
these angles lose a degree of freedom (gimbal lock): ω and κ turn about the same axis,
their derivatives become parallel and a Gauss-Newton step in them is long and poor.
Close-range networks look in every direction, and from a start 20° off some images
pass near that pole. A step in a small rotation δ of the image frame,
R(δ) = R·exp([δ]×), has no such pole: ∂R/∂δ_k = R·[e_k]×.

The bundle takes such steps while the start is poor (σ0 of the linearisation point at
least ``BundleOptions.local_sigma0`` and the last step not yet small) and only if nothing else
refers to the angles (no observed attitudes, additional parameters or auxiliary
data); the last steps — those the stopping rule judges and the precision reuses — are
always taken in ω, φ, κ. :func:`apply_local` turns R(δ) back into the angles;
:func:`angle_map` relates the two parametrisations to first order, so that the factored
normal matrix of a small step in δ can serve the next steps in ω, φ, κ (chord steps,
``BundleOptions.chord_reuse``, :mod:`orientviz.bundle.loop._steps`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...rotation import matrix_derivatives, matrix_from_opk, matrix_from_rotvec, opk_from_matrix

F64 = NDArray[np.float64]

#: [e_k]× for k = 0, 1, 2.
_GENERATORS = np.array(
    [
        [[0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]],
        [[0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [-1.0, 0.0, 0.0]],
        [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]],
    ]
)


def local_derivatives(R: F64) -> F64:
    """∂R/∂δ_k = R·[e_k]× at δ = 0, shape (m, 3, 3, 3) as ``matrix_derivatives`` stacked."""
    return np.einsum("mij,kjl->mkil", R, _GENERATORS)


def apply_local(angles: F64, delta: F64, sequence: str = "opk") -> F64:
    """Angles (m, 3) of R(angles)·exp([δ]×) for small rotations δ (m, 3) in rad."""
    R = matrix_from_opk(angles[:, 0], angles[:, 1], angles[:, 2], sequence)
    Rn = R @ matrix_from_rotvec(delta)
    out = np.column_stack(opk_from_matrix(Rn, sequence)).reshape(-1, 3)
    # keep each angle on the branch nearest the old one (no 2π jumps in the history)
    return angles + (out - angles + np.pi) % (2 * np.pi) - np.pi


def frame_axials(angles: F64, sequence: str = "opk", local: bool = False) -> F64:
    """Axial vectors ω_θ of (∂R/∂θ)ᵀ R per image and angle, shape (m, 3 θ, 3).

    (∂R/∂θ)ᵀ R is skew-symmetric (R orthonormal); its axial vector is taken averaged over
    the two entries of each component. θ: ω, φ, κ, or with ``local`` the rotations δ of
    the image frame. The collinearity kernel's derivatives by θ are ω_θ × (u, v, w)
    (:mod:`orientviz.bundle.model._kernel`); −ω_θ are the columns of :func:`angle_map`.
    """
    R = matrix_from_opk(angles[:, 0], angles[:, 1], angles[:, 2], sequence)
    if local:
        dR = local_derivatives(R)
    else:
        dR = np.stack(matrix_derivatives(angles[:, 0], angles[:, 1], angles[:, 2], sequence), 1)
    M = dR.transpose(0, 1, 3, 2) @ R[:, None]
    return 0.5 * np.stack(
        [
            M[:, :, 2, 1] - M[:, :, 1, 2],
            M[:, :, 0, 2] - M[:, :, 2, 0],
            M[:, :, 1, 0] - M[:, :, 0, 1],
        ],
        axis=2,
    )


def angle_map(angles: F64, sequence: str = "opk") -> F64:
    """The map A (m, 3, 3) from changes of ω, φ, κ to rotations of the image frame.

    ∂R/∂θ = R·[a_θ]× with a_θ the axial vector of Rᵀ ∂R/∂θ = −(∂R/∂θ)ᵀ R, i.e. −ω_θ of
    :func:`frame_axials`; A's columns are a_ω, a_φ, a_κ, so a change dθ of the angles
    rotates the frame by δ = A·dθ (first order) and the Jacobians relate as J_θ = J_δ·A
    (the chord step's change of parametrisation in
    :class:`orientviz.bundle.loop._steps.BundleSteps`).
    """
    return -frame_axials(angles, sequence).transpose(0, 2, 1)
