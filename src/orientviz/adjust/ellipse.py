"""Standard error ellipses of 2-D estimates and their confidence scale factors.

A 2×2 covariance matrix C = [[σx², σxy], [σxy, σy²]] (units², e.g. m²) describes the
precision of a point in a plane. Its *standard error ellipse* has the semi-axes

    a², b² = (σx² + σy²)/2 ± w,   w = √(((σx² − σy²)/2)² + σxy²),

(a ≥ b, the square roots of the eigenvalues of C) and the major axis at the angle
θ = ½ atan2(2 σxy, σx² − σy²) from the x axis, counter-clockwise. A normally distributed
estimate lies inside the standard ellipse with probability 1 − e^(−1/2) ≈ 39.3 %; the
ellipse scaled by k = √(χ²₂(p)) = √(−2 ln(1 − p)) holds it with probability p.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class ErrorEllipse:
    """Semi-axes and orientation of standard error ellipses (vectorised).

    Attributes
    ----------
    a, b : ndarray
        Major and minor semi-axis, in the units of the coordinates (a ≥ b ≥ 0).
    theta : ndarray
        Angle of the major axis from the x axis, counter-clockwise, rad in (−π/2, π/2].
    """

    a: F64
    b: F64
    theta: F64


def error_ellipse(cov: ArrayLike) -> ErrorEllipse:
    """Standard error ellipse(s) of 2×2 covariance matrices.

    Parameters
    ----------
    cov : array_like, shape (2, 2) or (n, 2, 2)
        Covariance matrices, units² (m², mm²…); a larger matrix (…, 3, 3) uses its
        upper-left 2×2 block (the planimetric part of a 3-D point).

    Returns
    -------
    ErrorEllipse
        Semi-axes in the coordinates' units, angle in rad; scalars come back as 0-d arrays.
    """
    C = np.asarray(cov, dtype=float)
    if C.ndim < 2 or C.shape[-1] < 2 or C.shape[-2] < 2 or C.shape[-1] != C.shape[-2]:
        raise InputError(f"expected covariance matrices of shape (..., 2, 2), got {C.shape}")
    qxx, qyy, qxy = C[..., 0, 0], C[..., 1, 1], C[..., 0, 1]
    mean = 0.5 * (qxx + qyy)
    w = np.hypot(0.5 * (qxx - qyy), qxy)
    a = np.sqrt(np.clip(mean + w, 0.0, None))
    b = np.sqrt(np.clip(mean - w, 0.0, None))
    theta = 0.5 * np.arctan2(2.0 * qxy, qxx - qyy)
    return ErrorEllipse(a, b, theta)


def confidence_scale(p: float, dof: int = 2) -> float:
    """Factor k that turns a standard ellipse (dof = 2) or interval (dof = 1) into a
    confidence region of probability ``p``: k = √(χ²_dof(p)).

    Parameters
    ----------
    p : float
        Probability, 0 < p < 1 (e.g. 0.95).
    dof : {1, 2}
        1 for an interval (k = 1.96 at p = 0.95), 2 for an ellipse (k = 2.448).
    """
    if not 0.0 < p < 1.0:
        raise InputError(f"expected a probability 0 < p < 1, got {p}")
    if dof == 2:
        return math.sqrt(-2.0 * math.log1p(-p))
    if dof == 1:
        from scipy.special import erfinv

        return math.sqrt(2.0) * float(erfinv(p))
    raise InputError(f"expected dof 1 or 2, got {dof}")


def ellipse_outline(centre: ArrayLike, cov: ArrayLike, k: float = 1.0, n: int = 100) -> F64:
    """Points (n, 2) on the ellipse k·(standard ellipse) around ``centre`` (for plotting)."""
    e = error_ellipse(np.asarray(cov, dtype=float)[:2, :2])
    t = np.linspace(0.0, 2.0 * np.pi, n)
    ca, sa = math.cos(float(e.theta)), math.sin(float(e.theta))
    u, v = k * float(e.a) * np.cos(t), k * float(e.b) * np.sin(t)
    c = np.asarray(centre, dtype=float)[:2]
    return np.column_stack([c[0] + ca * u - sa * v, c[1] + sa * u + ca * v])


def inside_fraction(samples: ArrayLike, centre: ArrayLike, cov: ArrayLike, k: float = 1.0) -> float:
    """Share of 2-D ``samples`` inside k·(standard ellipse): Mahalanobis distance ≤ k."""
    d = np.asarray(samples, dtype=float)[:, :2] - np.asarray(centre, dtype=float)[:2]
    Ci = np.linalg.inv(np.asarray(cov, dtype=float)[:2, :2])
    m2 = np.einsum("ni,ij,nj->n", d, Ci, d)
    return float(np.mean(m2 <= k * k))
