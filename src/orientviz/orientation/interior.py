"""Interior orientation of a scanned or measured film image from its fiducial marks.

A film image is measured in a machine frame (comparator or scanner: ξ, η in mm, or
pixels times the pixel size). The camera's calibration certificate gives the fiducial
marks' coordinates (x, y) in the image frame (mm, origin near the principal point). The
transformation from the machine frame to the image frame is fitted to the fiducials:

* ``"affine"`` (6 parameters) — x = a0 + a1 ξ + a2 η,  y = b0 + b1 ξ + b2 η: shift,
  rotation, two scales and a shear. It takes up the film's uneven shrinkage (different
  along and across the film) and a non-orthogonal machine; the usual choice with 4 or 8
  marks.
* ``"similarity"`` (4 parameters) — x = a0 + a ξ − b η,  y = b0 + b ξ + a η: one scale.
  What is left in its residuals is the affine film deformation.

:func:`fiducial_transformation` returns an :class:`~orientviz.adjust.result.Adjustment`
(residuals in mm, σ0, cofactors); :func:`apply_interior` maps measured points;
:func:`affine_parameters` names the affine's geometry (scales, rotation, shear).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..adjust.engine import gauss_newton
from ..adjust.result import Adjustment
from ..errors import InputError

F64 = NDArray[np.float64]

#: Parameter names of the two models.
NAMES: dict[str, list[str]] = {
    "affine": ["a0", "a1", "a2", "b0", "b1", "b2"],
    "similarity": ["a0", "a", "b", "b0"],
}


def interior_design(machine: ArrayLike, model: str = "affine") -> F64:
    """Design matrix (2n, u) of the fiducial transformation, rows x1, y1, x2, y2, …"""
    m = np.asarray(machine, dtype=float)
    n = len(m)
    xi, eta, one, zero = m[:, 0], m[:, 1], np.ones(n), np.zeros(n)
    if model == "affine":
        rx = np.column_stack([one, xi, eta, zero, zero, zero])
        ry = np.column_stack([zero, zero, zero, one, xi, eta])
    elif model == "similarity":
        rx = np.column_stack([one, xi, -eta, zero])
        ry = np.column_stack([zero, eta, xi, one])
    else:
        raise InputError(f"expected model 'affine' or 'similarity', got {model!r}")
    A = np.empty((2 * n, rx.shape[1]))
    A[0::2], A[1::2] = rx, ry
    return A


def fiducial_transformation(machine: ArrayLike, calibrated: ArrayLike, *, model: str = "affine",
                            sigma: float = 0.002) -> Adjustment:  # fmt: skip
    """Fit the machine → image transformation to the fiducial marks.

    Parameters
    ----------
    machine : array_like, shape (n, 2)
        Measured fiducial positions ξ, η in the machine frame, mm.
    calibrated : array_like, shape (n, 2)
        Their calibrated image coordinates x, y, mm.
    model : {"affine", "similarity"}
        6 or 4 parameters (see the module docstring).
    sigma : float
        A-priori σ of a calibrated coordinate as reproduced by a measurement, mm.

    Returns
    -------
    Adjustment
        ``x`` the parameters (:data:`NAMES`), ``residuals`` (2n,) mm as x1, y1, x2, …
        (transformed − calibrated), ``sigma0``, ``cofactor``.
    """
    m = np.asarray(machine, dtype=float)
    xy = np.asarray(calibrated, dtype=float)
    if m.ndim != 2 or m.shape[1] != 2 or xy.shape != m.shape:
        raise InputError(f"expected two point sets of shape (n, 2), got {m.shape} and {xy.shape}")
    A = interior_design(m, model)
    need = {"affine": 3, "similarity": 2}[model]
    if len(m) < need:
        raise InputError(
            f"the {model} transformation needs at least {need} fiducials, got {len(m)}"
        )
    x0 = np.zeros(A.shape[1])
    return gauss_newton(lambda x: (A @ x, A), x0, xy.reshape(-1), sigma, names=NAMES[model],
                        max_iter=3, context=f"{model} fiducial transformation")  # fmt: skip


def apply_interior(params: ArrayLike, machine: ArrayLike, model: str = "affine") -> F64:
    """Image coordinates (n, 2) in mm of machine coordinates (n, 2) by fitted parameters."""
    m = np.asarray(machine, dtype=float)
    return (interior_design(m, model) @ np.asarray(params, dtype=float)).reshape(-1, 2)


@dataclass(frozen=True)
class AffineGeometry:
    """The affine transformation x = t + A ξ read as scales, rotation and shear.

    A = R(α) · [[sx, 0], [0, sy]] · [[1, k], [0, 1]]: the machine's ξ axis is scaled by sx
    and turned by α; η is scaled by sy and sheared by k (the axes are not perpendicular by
    ≈ k rad).

    Attributes
    ----------
    scale_x, scale_y : float
        Scales of the ξ and η axes (image mm per machine mm).
    rotation : float
        α, rad, counter-clockwise.
    shear : float
        k, dimensionless (≈ rad).
    """

    scale_x: float
    scale_y: float
    rotation: float
    shear: float


def affine_parameters(params: ArrayLike) -> AffineGeometry:
    """Scales, rotation and shear of affine parameters (a0, a1, a2, b0, b1, b2)."""
    a0, a1, a2, b0, b1, b2 = np.asarray(params, dtype=float)
    alpha = math.atan2(b1, a1)
    sx = math.hypot(a1, b1)
    ca, sa = math.cos(alpha), math.sin(alpha)
    # Rᵀ A = [[sx, sx k], [0, sy]]
    u = ca * a2 + sa * b2
    sy = -sa * a2 + ca * b2
    return AffineGeometry(float(sx), float(sy), float(alpha), float(u / sx))
