"""A pair of radar panorama images: intersection, relative and absolute orientation.

Geier (1973), task 4. Each image point fixes two surfaces: the range sphere about its
station (4b) and the azimuth plane ε through the station and the axis (4c). Two images
give four equations for the three coordinates of an object point, so every homologous
pair yields exactly one condition. It is weak where ε1 and ε2 are nearly parallel or
where their line of intersection touches a sphere.

* :func:`intersect` — object points from two oriented images (closed form on the
  projection circle of image 1, refined by least squares).
* :func:`relative_orientation` — task 4a: the second image's six exterior parameters
  (or ten, with its interior orientation) with the first image fixed, adjusting all
  four image coordinates of every pair with the object points as unknowns (the
  Gauss-Markov form of the condition equations).
* :func:`absolute_orientation` — task 4b: a rigid transformation (three rotations, three
  shifts, no scale — radar ranges carry the scale) of the model into control.

Units: metres; angles in radians; rotations as in :mod:`orientviz.radar.ppi`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..adjust import Adjustment, gauss_newton
from ..adjust.rank import null_space_of_normal
from ..errors import InputError, NotDeterminableError
from ..rotation import matrix_derivatives, matrix_from_opk, opk_from_matrix
from .orientation import RadarResult, _indices
from .ppi import (
    EXTERIOR,
    PARAMS,
    RadarImage,
    azimuth_direction,
    check_image_points,
    check_points,
    project_with_jacobian,
    sphere_radius,
    tolerant,
)

F64 = NDArray[np.float64]


@dataclass
class RadarPairResult(RadarResult):
    """Task 4a's result: image 2 relative to image 1 and the model points.

    Attributes
    ----------
    points : ndarray, shape (n, 3)
        The model points (in image 1's object frame), m.
    """

    points: F64 | None = None


@dataclass
class RadarAbsoluteResult(Adjustment):
    """Task 4b's result: the rigid transformation of a radar model onto control.

    Attributes
    ----------
    transformed : ndarray, shape (n, 3)
        The model points in the object frame, m.
    task : str
        ``"absolute orientation"``.
    """

    transformed: F64 | None = None
    task: str = "absolute orientation"


def circle_sphere_candidates(xy1: ArrayLike, image1: RadarImage, s2: ArrayLike, X02: ArrayLike):
    """Points of image 1's projection circles at distance ``s2`` from ``X02``.

    Parameters
    ----------
    xy1 : array_like, shape (n, 2)
        Image coordinates in image 1, m.
    image1 : RadarImage
    s2 : array_like, shape (n,)
        Slant ranges from the second station, m.
    X02 : array_like, shape (3,)
        The second station, m.

    Returns
    -------
    low, high : ndarray, shape (n, 3)
        The two solutions, ``low`` the one further towards −k of image 1 (below the
        station for a vertical axis). NaN where the circle misses the sphere.
    """
    r1 = sphere_radius(xy1, image1)
    e1 = azimuth_direction(xy1, image1)
    k = image1.axis
    X01 = np.asarray(image1.X0, float)
    D = X01 - np.asarray(X02, float)
    # |D + r1 (cos t e1 + sin t k)|² = s2²  →  A cos t + B sin t = C
    A = 2 * r1 * (e1 @ D)
    B = np.full_like(r1, 2 * (k @ D)) * r1
    C = np.asarray(s2, float) ** 2 - D @ D - r1**2
    R = np.hypot(A, B)
    with np.errstate(invalid="ignore"):
        base = np.arctan2(B, A)
        delta = np.arccos(C / R)
    t_lo, t_hi = base - delta, base + delta
    out = []
    for t in (t_lo, t_hi):
        out.append(X01 + r1[:, None] * (np.cos(t)[:, None] * e1 + np.sin(t)[:, None] * k))
    lo, hi = out
    swap = (lo - X01) @ k > (hi - X01) @ k
    lo[swap], hi[swap] = hi[swap], lo[swap].copy()
    return lo, hi


def intersect(
    xy1: ArrayLike,
    image1: RadarImage,
    xy2: ArrayLike,
    image2: RadarImage,
    *,
    below: bool = True,
    refine: bool = True,
) -> F64:
    """Object points from homologous image points of two oriented images, m (n, 3).

    The closed-form start lies on image 1's projection circle at image 2's range (the
    candidate below image 1's station if ``below``); ``refine`` then adjusts the four
    image coordinates per point by least squares (3 unknowns each).
    """
    L1 = check_image_points(xy1)
    L2 = check_image_points(xy2)
    if L1.shape != L2.shape:
        raise InputError(f"expected as many points in both images, got {len(L1)} and {len(L2)}")
    lo, hi = circle_sphere_candidates(L1, image1, sphere_radius(L2, image2), image2.X0)
    X = lo if below else hi
    miss = ~np.all(np.isfinite(X), axis=1)
    if np.any(miss):
        # the circle misses the sphere (rounding): take the circle point closest to it
        r1 = sphere_radius(L1[miss], image1)
        X[miss] = np.asarray(image1.X0) + r1[:, None] * azimuth_direction(L1[miss], image1)
    if not refine:
        return X
    for _ in range(10):
        xy_a, _, Ja = project_with_jacobian(X, image1, image_terms=False)
        xy_b, _, Jb = project_with_jacobian(X, image2, image_terms=False)
        J = np.concatenate([Ja, Jb], axis=1)  # (n, 4, 3)
        r = np.concatenate([L1 - xy_a, L2 - xy_b], axis=1)
        N = np.einsum("nki,nkj->nij", J, J)
        b = np.einsum("nki,nk->ni", J, r)
        dX = np.linalg.solve(N, b[..., None])[..., 0]
        X = X + dX
        if np.abs(dX).max() < 1e-7:
            break
    return X


def relative_orientation(
    xy1: ArrayLike,
    image1: RadarImage,
    xy2: ArrayLike,
    approx2: RadarImage,
    *,
    free: Sequence[str] = EXTERIOR,
    sigma: float = 1.0,
    points0: ArrayLike | None = None,
    **engine,
) -> RadarPairResult:
    """Task 4a: orient image 2 to the fixed image 1 from homologous points alone.

    Parameters
    ----------
    xy1, xy2 : array_like, shape (n, 2)
        Homologous image coordinates in m.
    image1 : RadarImage
        The first image, all ten parameters known (it defines the model frame).
    approx2 : RadarImage
        Approximate values for image 2 (its fixed parameters at their known values).
    free : sequence of str
        Unknowns of image 2: the six exterior parameters (default, interior known) or
        all ten (``PARAMS``: the interior orientation of image 2 differs).
    sigma : float
        A-priori σ of an image coordinate, m.
    points0 : array_like, shape (n, 3), optional
        Approximate object points (default: :func:`intersect` with ``approx2``).
    **engine
        Passed to :func:`~orientviz.adjust.gauss_newton`.

    Returns
    -------
    RadarPairResult
        Parameters: image 2's unknowns, then the points (block ``"points"``);
        ``image`` is image 2, ``points`` (n, 3) the model points.
        Redundancy 4n − 3n − len(free) = n − len(free).
    """
    L1, L2 = check_image_points(xy1), check_image_points(xy2)
    n = len(L1)
    free = list(free)
    idx = _indices(free)
    k = len(free)
    if L2.shape != L1.shape:
        raise InputError(f"expected as many points in both images, got {n} and {len(L2)}")
    if n < k:
        raise NotDeterminableError(
            f"relative orientation: {n} homologous points give {n} conditions for "
            f"{k} unknowns ({', '.join(free)}); need at least {k}",
            free,
            k - n,
        )
    X0 = (
        check_points(points0)
        if points0 is not None
        else intersect(L1, image1, L2, approx2, refine=True)
    )
    equations = relative_equations(image1, approx2, free, n)
    full0 = approx2.vector()
    seq = approx2.sequence
    names = free + [f"P{i + 1}.{c}" for i in range(n) for c in "XYZ"]
    l = np.concatenate([L1.reshape(-1), L2.reshape(-1)])
    labels = [f"img{j}/{i + 1}/{c}" for j in (1, 2) for i in range(n) for c in "xy"]
    engine.setdefault("tol", 1e-8)
    u0 = np.concatenate([full0[idx], X0.reshape(-1)])
    try:
        res = gauss_newton(
            tolerant(equations, 4 * n, k + 3 * n),
            u0,
            l,
            sigma,
            names=names,
            groups={"image2": slice(0, k), "points": slice(k, k + 3 * n)},
            obs_labels=labels,
            context="relative orientation",
            **engine,
        )
    except NotDeterminableError as exc:
        raise _orientation_defect(equations, u0, free, exc) from None
    p = full0.copy()
    p[idx] = res.x[:k]
    return res.extend(
        RadarPairResult,
        image=RadarImage.from_vector(p, seq),
        points=res.x[k:].reshape(n, 3),
        task="relative orientation",
    )


def _orientation_defect(equations, u0: F64, free: list[str], exc: NotDeterminableError):
    """Re-state a singular relative orientation in terms of image 2's parameters.

    The null space spans orientation parameters *and* points; the user needs to know
    which orientation parameters move in it (the points just follow).
    """
    _, J = equations(u0)
    null = null_space_of_normal(J.T @ J)
    k = len(free)
    if null.shape[1] == 0:
        return exc
    share = np.sum(null[:k] ** 2, axis=1)
    order = np.argsort(-share)
    names = [free[i] for i in order if share[i] > 1e-6 * max(share.max(), 1e-300)]
    what = ", ".join(names) if names else "only object points"
    return NotDeterminableError(
        f"relative orientation: {null.shape[1]} parameter combination(s) not determinable "
        f"from the homologous points; image 2 parameters involved: {what} (with the object "
        "points, which follow them)",
        names or exc.parameters,
        null.shape[1],
    )


def relative_equations(image1: RadarImage, approx2: RadarImage, free: Sequence[str], n: int):
    """The functional model of a relative orientation with ``n`` homologous points.

    Returns ``equations(u) -> (f, J)`` with u = (image 2's free parameters, X1, Y1, Z1, …,
    Zn) and f = (image-1 coordinates x1, y1, …, then image-2 coordinates), m.
    """
    idx = _indices(free)
    k = len(idx)
    seq = approx2.sequence
    full0 = approx2.vector()
    # row of image coordinate c of point i: 2i + c (image 1), 2n + 2i + c (image 2); the
    # point's columns k + 3i … k + 3i + 2: index arrays shaped like the Jacobians' blocks
    rows1 = (2 * np.arange(n)[:, None] + np.arange(2)[None, :])[:, :, None]  # (n, 2, 1)
    rows2 = rows1 + 2 * n
    cols = (k + 3 * np.arange(n)[:, None] + np.arange(3)[None, :])[:, None, :]  # (n, 1, 3)
    own = np.arange(k)[None, None, :]

    def equations(u: F64):
        p = full0.copy()
        p[idx] = u[:k]
        X = u[k:].reshape(n, 3)
        xa, _, Ja = project_with_jacobian(X, image1, image_terms=False)
        xb, Jib, Jb = project_with_jacobian(X, RadarImage.from_vector(p, seq))
        J = np.zeros((4 * n, k + 3 * n))
        J[rows1, cols] = Ja
        J[rows2, own] = Jib[:, :, idx]
        J[rows2, cols] = Jb
        return np.concatenate([xa.reshape(-1), xb.reshape(-1)]), J

    return equations


def absolute_orientation(
    model_points: ArrayLike,
    control: ArrayLike,
    *,
    sigma: float | ArrayLike = 1.0,
    sequence: str = "pok",
    **engine,
) -> RadarAbsoluteResult:
    """Task 4b: rigid transformation X = T + R(φ, ω, κ) · x of the model into control.

    No scale: the radar model already has true scale. Six coordinates (e.g. two full
    control points and two heights, not all on one line) are the minimum.

    Parameters
    ----------
    model_points : array_like, shape (n, 3)
        Points in the model frame, m.
    control : array_like, shape (n, 3)
        Their object coordinates, m; NaN marks a coordinate that is not known.
    sigma : float or array_like
        A-priori σ of a control coordinate, m.
    sequence : {"pok", "opk"}
        Rotation sequence of φ, ω, κ (R = R_φ R_ω R_κ by default).

    Returns
    -------
    RadarAbsoluteResult
        Parameters ``TX, TY, TZ, phi, omega, kappa``; ``transformed`` (n, 3) m.
    """
    x = check_points(model_points, "model points")
    C = np.asarray(control, dtype=float)
    if C.shape != x.shape:
        raise InputError(f"expected control of shape {x.shape}, got {C.shape}")
    known = np.isfinite(C)
    nobs = int(known.sum())
    if nobs < 6:
        raise NotDeterminableError(
            f"absolute orientation: {nobs} control coordinates for 6 unknowns "
            "(TX, TY, TZ, phi, omega, kappa); need at least 6",
            ["TX", "TY", "TZ", "phi", "omega", "kappa"],
            6 - nobs,
        )
    full = np.all(known, axis=1)
    u0 = np.zeros(6)
    if full.sum() >= 3:
        u0 = _rigid_start(x[full], C[full], sequence)
    elif full.any():
        u0[:3] = (C[full] - x[full]).mean(axis=0)

    def equations(u: F64):
        R = matrix_from_opk(u[4], u[3], u[5], sequence)
        dRo, dRp, dRk = matrix_derivatives(u[4], u[3], u[5], sequence)
        X = u[:3] + x @ R.T
        J = np.zeros((len(x), 3, 6))
        J[:, :, :3] = np.eye(3)
        for c, dR in ((3, dRp), (4, dRo), (5, dRk)):
            J[:, :, c] = x @ dR.T
        return X[known], J[known]

    engine.setdefault("tol", 1e-8)
    names = ["TX", "TY", "TZ", "phi", "omega", "kappa"]
    res = gauss_newton(
        equations, u0, C[known], sigma, names=names, context="absolute orientation", **engine
    )
    R = matrix_from_opk(res.x[4], res.x[3], res.x[5], sequence)
    return res.extend(RadarAbsoluteResult, transformed=res.x[:3] + x @ R.T)


def _rigid_start(x: F64, X: F64, sequence: str) -> F64:
    """Closed-form rigid fit (SVD) as start values: TX, TY, TZ, φ, ω, κ."""
    cx, cX = x.mean(0), X.mean(0)
    U, _, Vt = np.linalg.svd((X - cX).T @ (x - cx))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    R = U @ D @ Vt
    om, ph, ka = opk_from_matrix(R, sequence)
    T = cX - R @ cx
    return np.array([*T, float(ph), float(om), float(ka)])


__all__ = [
    "PARAMS",
    "absolute_orientation",
    "circle_sphere_candidates",
    "intersect",
    "relative_orientation",
]
