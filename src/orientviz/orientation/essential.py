"""The modern route to relative orientation: the essential matrix.

For a pair with the left bundle as the model frame (R1 = I, O1 = 0) and the right one
at O2 = B with rotation R2 (image → model, :mod:`orientviz.rotation`), the image rays
``d = (x, y, −c)`` (mm, orientviz's camera frame: x right, y up, z backwards) satisfy
the coplanarity condition

    d1ᵀ E d2 = 0,   E = [B]ₓ R2,

the model point being λ1 d1 = B + λ2 R2 d2 with λ1, λ2 > 0 (in front of both images).
:func:`eight_point` estimates E linearly (normalised eight-point algorithm),
:func:`decompose_essential` gives the four (R, t) factorisations and
:func:`select_by_cheirality` keeps the one with the points in front of both images;
:func:`essential_route` then scales the base to bx = b, converts to the five elements
of a dependent pair and refines them with the rigorous model
(:func:`~orientviz.orientation.relative.relative_orientation`).

OpenCV's camera frame is x right, y down, z forwards: its normalised coordinates are
(x/c, −y/c) and its (R, t) map camera-1 into camera-2 coordinates, so
``R2 = D R_cvᵀ D`` and ``B ∝ −R2 D t_cv`` with D = diag(1, −1, −1).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..adjust.result import Adjustment
from ..errors import InputError, NotDeterminableError
from ..rotation import check_sequence, opk_from_matrix, skew
from .relative import check_points, relative_orientation

F64 = NDArray[np.float64]

#: OpenCV's camera frame in orientviz's: diag(1, −1, −1).
D_OPENCV: F64 = np.diag([1.0, -1.0, -1.0])


def essential_from_orientation(R2: ArrayLike, base: ArrayLike) -> F64:
    """E = [B]ₓ R2 with d1ᵀ E d2 = 0 (see the module docstring)."""
    return skew(np.asarray(base, dtype=float)) @ np.asarray(R2, dtype=float)


def _homogeneous(xy: F64, c: float) -> F64:
    # (−x/c, −y/c, 1) is parallel to the ray (x, y, −c)
    return np.column_stack([-xy[:, 0] / c, -xy[:, 1] / c, np.ones(xy.shape[0])])


def _normaliser(q: F64) -> F64:
    m = q[:, :2].mean(axis=0)
    s = np.sqrt(2.0) / max(np.mean(np.linalg.norm(q[:, :2] - m, axis=1)), 1e-300)
    return np.array([[s, 0, -s * m[0]], [0, s, -s * m[1]], [0, 0, 1.0]])


def eight_point(xy_left: ArrayLike, xy_right: ArrayLike, c: float) -> F64:
    """Essential matrix by the normalised eight-point algorithm (n ≥ 8 pairs).

    Parameters
    ----------
    xy_left, xy_right : array_like, shape (n, 2)
        Image coordinates in mm, reduced to the principal point.
    c : float
        Principal distance, mm.

    Returns
    -------
    ndarray, shape (3, 3)
        E with d1ᵀ E d2 = 0 for rays d = (x, y, −c), singular values (1, 1, 0).

    Raises
    ------
    InputError
        Fewer than 8 points or mismatched shapes.
    NotDeterminableError
        The points do not determine E (fewer than 8 independent constraints).
    """
    q1 = _homogeneous(check_points(xy_left, "xy_left"), c)
    q2 = _homogeneous(check_points(xy_right, "xy_right"), c)
    if q1.shape != q2.shape:
        raise InputError(
            f"expected two point sets of the same shape, got {q1.shape} and {q2.shape}"
        )
    if q1.shape[0] < 8:
        raise InputError(f"the eight-point algorithm needs at least 8 points, got {q1.shape[0]}")
    T1, T2 = _normaliser(q1), _normaliser(q2)
    a, bb = q1 @ T1.T, q2 @ T2.T
    M = (a[:, :, None] * bb[:, None, :]).reshape(-1, 9)
    _, s, Vt = np.linalg.svd(M, full_matrices=False)
    if s.size < 9 or s[-2] < 1e-10 * s[0]:
        raise NotDeterminableError(
            "the points do not determine the essential matrix (fewer than 8 independent "
            "constraints: degenerate or planar-critical configuration)",
            parameters=["E"],
            defect=1,
        )
    En = Vt[-1].reshape(3, 3)
    E = T1.T @ En @ T2
    U, sv, Vt2 = np.linalg.svd(E)
    E = U @ np.diag([1.0, 1.0, 0.0]) @ Vt2
    return E / np.linalg.norm(E) * np.sqrt(2.0)


def decompose_essential(E: ArrayLike) -> list[tuple[F64, F64]]:
    """The four factorisations E ∝ [t]ₓ R: (R, t) with R proper, |t| = 1."""
    U, _, Vt = np.linalg.svd(np.asarray(E, dtype=float))
    if np.linalg.det(U) < 0:
        U = -U
    if np.linalg.det(Vt) < 0:
        Vt = -Vt
    W = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    t = U[:, 2]
    out = []
    for R in (U @ W @ Vt, U @ W.T @ Vt):
        for s in (1.0, -1.0):
            out.append((R, s * t))
    return out


def depths(xy_left: F64, xy_right: F64, c: float, R: F64, t: F64) -> tuple[F64, F64]:
    """λ1, λ2 of λ1 d1 ≈ t + λ2 R d2 per point (least squares, vectorised)."""
    d1 = np.column_stack([xy_left, np.full(len(xy_left), -c)])
    d2 = np.column_stack([xy_right, np.full(len(xy_right), -c)]) @ R.T
    a11 = (d1 * d1).sum(1)
    a12 = -(d1 * d2).sum(1)
    a22 = (d2 * d2).sum(1)
    r1 = d1 @ t
    r2 = -(d2 @ t)
    det = a11 * a22 - a12 * a12
    with np.errstate(divide="ignore", invalid="ignore"):
        lam1 = (a22 * r1 - a12 * r2) / det
        lam2 = (a11 * r2 - a12 * r1) / det
    return lam1, lam2


def select_by_cheirality(
    E: ArrayLike, xy_left: ArrayLike, xy_right: ArrayLike, c: float
) -> tuple[F64, F64, int]:
    """The factorisation with most points in front of both images.

    Returns
    -------
    R : ndarray, shape (3, 3)
        Rotation of the right image (image → model frame of the left image).
    t : ndarray, shape (3,)
        Unit base direction O2 − O1.
    n_front : int
        Number of points with λ1 > 0 and λ2 > 0.
    """
    xy1 = check_points(xy_left, "xy_left")
    xy2 = check_points(xy_right, "xy_right")
    best = None
    for R, t in decompose_essential(E):
        l1, l2 = depths(xy1, xy2, c, R, t)
        n = int(np.sum((l1 > 0) & (l2 > 0)))
        if best is None or n > best[2]:
            best = (R, t, n)
    return best


def essential_route(
    xy_left: ArrayLike,
    xy_right: ArrayLike,
    c: float,
    *,
    b: float | None = None,
    sequence: str = "opk",
    sigma: float = 0.005,
    refine: bool = True,
) -> Adjustment:
    """Relative orientation via the essential matrix, refined by the rigorous model.

    Parameters
    ----------
    xy_left, xy_right : array_like, shape (n, 2)
        Image coordinates in mm (n ≥ 8).
    c : float
        Principal distance, mm.
    b : float, optional
        Model base bx; default the median x-parallax (model at about image scale).
    sequence : {"opk", "pok"}
        Rotation sequence of the returned angles.
    sigma : float
        A-priori σ of a y-parallax for the refinement, model units.
    refine : bool
        Refine with :func:`~orientviz.orientation.relative.relative_orientation`
        (default); otherwise return the linear solution only (no precision).

    Returns
    -------
    Adjustment
        Elements by, bz, ω, φ, κ of a dependent pair; ``extra`` holds ``"E"``,
        ``"R_linear"``, ``"t_linear"``, ``"linear"`` (the elements before refinement)
        and ``"n_front"``.
    """
    seq = check_sequence(sequence)
    xy1 = check_points(xy_left, "xy_left")
    xy2 = check_points(xy_right, "xy_right")
    E = eight_point(xy1, xy2, c)
    R, t, n_front = select_by_cheirality(E, xy1, xy2, c)
    if b is None:
        b = float(np.median(xy1[:, 0] - xy2[:, 0]))
    if abs(t[0]) < 1e-6:
        raise NotDeterminableError(
            "the base found from E has no component along x: the pair is not a "
            "dependent pair along X (by, bz cannot be scaled to bx = b)",
            parameters=["by", "bz"],
        )
    B = t * (b / t[0])
    lin = np.r_[B[1], B[2], np.array(opk_from_matrix(R, seq), dtype=float)]
    if refine:
        res = relative_orientation(xy1, xy2, c, b=b, approx=lin, sigma=sigma, sequence=seq)
    else:
        res = Adjustment(
            lin,
            ["by", "bz", "omega", "phi", "kappa"],
            float("nan"),
            len(xy1) - 5,
            np.zeros(len(xy1)),
            np.full(len(xy1), sigma),
            True,
            "linear solution only",
        )
    res.extra.update(E=E, R_linear=R, t_linear=t, linear=lin, n_front=n_front)
    return res
