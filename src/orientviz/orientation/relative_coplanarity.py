"""Relative orientation by the coplanarity condition.

The two rays of a point and the base lie in one plane (the epipolar plane) exactly when
the scalar triple product of the base and the two ray directions vanishes,

    F = B · (r1 × r2) = det [B; r1; r2] = 0,   r_i = R_i (x_i, y_i, −c)ᵀ / c,

with B = O2 − O1 = (b, by, bz) in model units and each image vector divided by the
principal distance (a dimensionless direction that reaches unit depth), so that F is a
length in model units: about the y-parallax times b/c in the normal case. The frame and
the five elements are those of :mod:`orientviz.orientation.relative` (dependent pair:
by, bz, ω, φ, κ of the right bundle; independent pair: φ1, κ1, φ2, ω2, κ2).

One condition per point ties four image coordinates together: a Gauss-Helmert model.
It is adjusted here in its classical reduced form, each F_i an observation of zero
whose variance is propagated from the image coordinates (σ_F² = σ_xy² ‖∂F_i/∂(x1, y1,
x2, y2)‖², linearised at the observed coordinates), so the residuals of the adjustment
*are* the triple products F_i at the estimated elements, and σ̂0 refers to the σ of an
image coordinate. The weights depend on the elements: they are computed at the start
values, and the adjustment is repeated from its result with new weights until they
stop changing (one or two repetitions).

Kovarik's y-parallax estimator adjusts the same condition divided by another factor
per point: :func:`~orientviz.orientation.relative.y_parallax` is p_y = −F / (r1z r2x −
r1x r2z) with these r. The collinearity method
(:mod:`orientviz.orientation.relative_collinearity`) adjusts all image coordinates with
the model points as unknowns. For error-free data the three agree exactly; with
measuring errors coplanarity and collinearity differ only in the second order of the
errors (one least-squares problem, linearised at the observations here), Kovarik's
estimator in the first order (another weighting).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..adjust.engine import gauss_newton
from ..adjust.result import Adjustment
from ..rotation import matrix_derivatives, matrix_from_opk

F64 = NDArray[np.float64]

#: Repeat the adjustment with new weights until no σ_F changes by more than this
#: fraction (at most :data:`MAX_REWEIGHT` adjustments).
REWEIGHT_TOLERANCE: float = 1e-6
MAX_REWEIGHT: int = 5


def _directions(xy: F64, angles: F64, c: float, sequence: str) -> tuple[F64, F64, list[F64]]:
    """Image vectors (x, y, −c)/c, turned by R, and R's derivatives applied to them."""
    d = np.empty((xy.shape[0], 3))
    d[:, :2] = xy / c
    d[:, 2] = -1.0
    R = matrix_from_opk(*angles, sequence=sequence)
    dR = matrix_derivatives(*angles, sequence=sequence)
    return d @ R.T, R, [d @ D.T for D in dR]


def triple_products(
    xy_left: ArrayLike,
    xy_right: ArrayLike,
    c: float,
    base: ArrayLike,
    angles_left: ArrayLike,
    angles_right: ArrayLike,
    sequence: str = "opk",
) -> F64:
    """The coplanarity misclosures F = B · (r1 × r2) of image-point pairs.

    Parameters
    ----------
    xy_left, xy_right : array_like, shape (n, 2)
        Image coordinates, mm, reduced to the principal point.
    c : float
        Principal distance, mm.
    base : array_like, shape (3,)
        B = O2 − O1 = (bx, by, bz), model units.
    angles_left, angles_right : array_like, shape (3,)
        ω, φ, κ of each bundle, radians.
    sequence : {"opk", "pok"}

    Returns
    -------
    ndarray, shape (n,)
        F_i = det [B; R1 (x1, y1, −c)/c; R2 (x2, y2, −c)/c], model units; zero when the
        two rays of point i meet.
    """
    r1, _, _ = _directions(np.asarray(xy_left, float), np.asarray(angles_left, float), c, sequence)
    r2, _, _ = _directions(
        np.asarray(xy_right, float), np.asarray(angles_right, float), c, sequence
    )
    return np.cross(r1, r2) @ np.asarray(base, float)


def _state(x: F64, b: float, kind: str) -> tuple[F64, F64, F64]:
    """Base, left and right angles (ω, φ, κ) of the five elements of ``kind``."""
    if kind == "dependent":
        return np.array([b, x[0], x[1]]), np.zeros(3), x[2:5]
    return np.array([b, 0.0, 0.0]), np.array([0.0, x[0], x[1]]), np.array([x[3], x[2], x[4]])


def _evaluate(xy1: F64, xy2: F64, c: float, b: float, kind: str, seq: str, x: F64):
    """F (n,), ∂F/∂elements (n, 5) and ‖∂F/∂(x1, y1, x2, y2)‖ (n,), per mm."""
    B, a1, a2 = _state(x, b, kind)
    r1, R1, dr1 = _directions(xy1, a1, c, seq)
    r2, R2, dr2 = _directions(xy2, a2, c, seq)
    cross = np.cross(r1, r2)
    F = cross @ B
    r2xB = np.cross(r2, B)  # F = r1 · (r2 × B)
    Bxr1 = np.cross(B, r1)  # F = r2 · (B × r1)
    J = np.empty((xy1.shape[0], 5))
    if kind == "dependent":
        J[:, 0] = cross[:, 1]
        J[:, 1] = cross[:, 2]
        for j in range(3):
            J[:, 2 + j] = (dr2[j] * Bxr1).sum(1)
    else:
        J[:, 0] = (dr1[1] * r2xB).sum(1)
        J[:, 1] = (dr1[2] * r2xB).sum(1)
        J[:, 2] = (dr2[1] * Bxr1).sum(1)
        J[:, 3] = (dr2[0] * Bxr1).sum(1)
        J[:, 4] = (dr2[2] * Bxr1).sum(1)
    # ∂F/∂x1 = R1[:, 0] · (r2 × B) / c, …: the image coordinates enter through r/c
    g = np.column_stack([r2xB @ R1[:, 0], r2xB @ R1[:, 1], Bxr1 @ R2[:, 0], Bxr1 @ R2[:, 1]])
    return F, J, np.sqrt((g * g).sum(1)) / c


def coplanarity_pair(
    xy1: F64,
    xy2: F64,
    c: float,
    b: float,
    kind: str,
    start: F64,
    sigma_image: float | Callable[[F64], float],
    sequence: str,
    labels: list[str] | None,
    max_iter: int,
) -> Adjustment:
    """Adjust the five elements from one coplanarity condition per point.

    Parameters
    ----------
    xy1, xy2 : ndarray, shape (n, 2)
        Image coordinates (mm), reduced to the principal point.
    c : float
        Principal distance (mm).
    b : float
        Base component bx (model units, held).
    kind : {"dependent", "independent"}
        Which five elements (see :mod:`orientviz.orientation.relative`).
    start : ndarray, shape (5,)
        Start values of the elements (model units, radians).
    sigma_image : float or callable
        A-priori σ of an image coordinate (mm), or a function of the elements giving
        it; the σ of each F is propagated from it.
    sequence : {"opk", "pok"}
    labels : list of str, optional
        Point labels (observations are labelled ``<id>/F``).
    max_iter : int
        Gauss-Newton steps per adjustment.

    Returns
    -------
    Adjustment
        ``x`` = the five elements; ``residuals`` = the triple products F_i (model units)
        at the estimate; ``sigma_obs`` = their propagated σ (model units).
    """
    n = xy1.shape[0]
    ids = labels or [str(i + 1) for i in range(n)]
    names = ["by", "bz", "omega", "phi", "kappa"]
    if kind != "dependent":
        names = ["phi1", "kappa1", "phi2", "omega2", "kappa2"]

    def equations(x: F64) -> tuple[F64, F64]:
        F, J, _ = _evaluate(xy1, xy2, c, b, kind, sequence, x)
        return F, J

    x = np.asarray(start, dtype=float).reshape(5)

    def sigmas(x: F64) -> F64:
        s_image = sigma_image(x) if callable(sigma_image) else float(sigma_image)
        return s_image * _evaluate(xy1, xy2, c, b, kind, sequence, x)[2]

    s = sigmas(x)
    history: list = []
    rounds = 0
    while rounds < MAX_REWEIGHT:
        rounds += 1
        res = gauss_newton(
            equations,
            x,
            np.zeros(n),
            s,
            names=names,
            obs_labels=[f"{p}/F" for p in ids],
            max_iter=max_iter,
            tol=1e-8,
            context="relative orientation (coplanarity)",
        )
        # one history over the repetitions (each step's σ̂0 with its round's weights)
        for it in res.history if not history else res.history[1:]:
            history.append(replace(it, index=len(history)))
        x = res.x
        s_new = sigmas(x)
        if np.max(np.abs(s_new / s - 1.0)) < REWEIGHT_TOLERANCE:
            break
        s = s_new
    res.history = history
    res.reason = f"{res.reason} (adjustment {rounds} with the weights at the last result)"
    return res
