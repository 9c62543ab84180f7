"""Epipolar geometry of an oriented pair: epipolar lines and normalised images.

Frames as in :mod:`orientviz.orientation.essential`: image rays d = (x, y, −c) (mm),
left bundle R1, right bundle R2 (image → model), base B = O2 − O1. The coplanarity
condition of two rays to one point is

    d1ᵀ E d2 = 0,   E = R1ᵀ [B]ₓ R2   (E = [B]ₓ R2 when R1 = I).

For a left image point, ``g = Eᵀ d1`` gives its **epipolar line** in the right image,
g0 x + g1 y − c g2 = 0 (:func:`epipolar_lines`); a correct match lies on it
(:func:`epipolar_distances`).

**Normalised images** (the normal case, "Normalbilder"): both bundles are turned to one
rotation R_n whose x axis is the base (:func:`normal_case_rotation`); the image points are
re-projected into these virtual images (:func:`normalise_points`). There E = [(b, 0, 0)]ₓ,
coplanarity reads y1' = y2' — the epipolar lines are image rows, the y-parallax of a point
is y1' − y2' — and the x-parallax p_x = x1' − x2' gives the point
λ d1' with λ = b / p_x (:func:`normal_case_points`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError
from ..rotation import skew
from .relative import check_points

F64 = NDArray[np.float64]


def _rays(xy: F64, c: float) -> F64:
    return np.column_stack([xy, np.full(len(xy), -float(c))])


def essential_matrix(R1: ArrayLike, R2: ArrayLike, base: ArrayLike) -> F64:
    """E = R1ᵀ [B]ₓ R2 with d1ᵀ E d2 = 0 (rays in each image's frame, mm)."""
    return np.asarray(R1, float).T @ skew(np.asarray(base, float)) @ np.asarray(R2, float)


def epipolar_lines(E: ArrayLike, xy_left: ArrayLike, c: float) -> F64:
    """Epipolar lines in the right image of left image points.

    Parameters
    ----------
    E : array_like, shape (3, 3)
        Essential matrix (d1ᵀ E d2 = 0).
    xy_left : array_like, shape (n, 2)
        Left image points, mm.
    c : float
        Principal distance, mm (both images).

    Returns
    -------
    ndarray, shape (n, 3)
        (a, b, d) with a x + b y + d = 0 in the right image (mm) and a² + b² = 1, so
        that a x + b y + d is the signed distance of (x, y) from the line in mm.
    """
    xy1 = check_points(xy_left, "xy_left")
    g = _rays(xy1, c) @ np.asarray(E, dtype=float)  # rows: (Eᵀ d1)ᵀ
    lines = np.column_stack([g[:, 0], g[:, 1], -float(c) * g[:, 2]])
    norm = np.hypot(lines[:, 0], lines[:, 1])
    if np.any(norm == 0):
        raise InputError("a left point maps to no line: E is zero or the point is an epipole")
    return lines / norm[:, None]


def epipolar_distances(E: ArrayLike, xy_left: ArrayLike, xy_right: ArrayLike, c: float) -> F64:
    """Signed distance (mm) of each right point from the epipolar line of its left partner."""
    xy2 = check_points(xy_right, "xy_right")
    L = epipolar_lines(E, xy_left, c)
    if len(L) != len(xy2):
        raise InputError(f"expected as many right as left points, got {len(xy2)} and {len(L)}")
    return L[:, 0] * xy2[:, 0] + L[:, 1] * xy2[:, 1] + L[:, 2]


def normal_case_rotation(R1: ArrayLike, R2: ArrayLike, base: ArrayLike) -> F64:
    """Common rotation R_n (image → model) of the two normalised images.

    Its x axis is the base direction, its z axis (towards the projection centres, "up")
    is as close as possible to the mean of the two images' z axes, y completes a
    right-handed frame.
    """
    B = np.asarray(base, dtype=float)
    x = B / np.linalg.norm(B)
    k = np.asarray(R1, float)[:, 2] + np.asarray(R2, float)[:, 2]
    y = np.cross(k, x)
    if np.linalg.norm(y) < 1e-12:
        raise InputError("the images look along the base: no normal case")
    y /= np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])


def normalise_points(xy: ArrayLike, R: ArrayLike, R_n: ArrayLike, c: float,
                     c_n: float | None = None) -> F64:  # fmt: skip
    """Image points (n, 2) in mm of an image with rotation R, re-projected into the
    normalised image with rotation R_n and principal distance c_n (default c)."""
    p = check_points(xy, "xy")
    d = _rays(p, c) @ (np.asarray(R_n, float).T @ np.asarray(R, float)).T
    cn = float(c if c_n is None else c_n)
    return -cn * d[:, :2] / d[:, 2:3]


def normal_case_points(xy_left_n: ArrayLike, xy_right_n: ArrayLike, c: float, b: float) -> F64:
    """Model points (n, 3) in the normal-case frame (origin O1, axes of R_n), units of b.

    λ = b / p_x with the x-parallax p_x = x1' − x2'; the point is λ (x1', ȳ', −c),
    ȳ' the mean of y1' and y2'.
    """
    p1 = check_points(xy_left_n, "xy_left_n")
    p2 = check_points(xy_right_n, "xy_right_n")
    px = p1[:, 0] - p2[:, 0]
    lam = float(b) / px
    ym = 0.5 * (p1[:, 1] + p2[:, 1])
    return np.column_stack([lam * p1[:, 0], lam * ym, -lam * float(c)])
