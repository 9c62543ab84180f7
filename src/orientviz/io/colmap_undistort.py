"""COLMAP's lens distortion inverted: undistorted normalised coordinates of pixels.

Used by :func:`orientviz.io.colmap.block_from_colmap` with ``lens="undistort"``: the
observations of SIMPLE_RADIAL, RADIAL and OPENCV cameras are undistorted with COLMAP's
fixed parameters (Newton's method, analytic 2 × 2 Jacobian, to :data:`UNDISTORT_TOL_PX`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError
from .colmap_text import ColmapCamera

#: The undistortion of an observation is iterated until it changes by less than this (px).
UNDISTORT_TOL_PX: float = 1e-10


def _coefficients(cam: ColmapCamera) -> tuple[float, float, float, float]:
    """k1, k2, p1, p2 of COLMAP's distortion (zeros where the model has none)."""
    p = cam.named()
    return p.get("k", p.get("k1", 0.0)), p.get("k2", 0.0), p.get("p1", 0.0), p.get("p2", 0.0)


def _distort(cam: ColmapCamera, x: NDArray[np.float64], y: NDArray[np.float64]):
    """COLMAP's forward distortion of normalised coordinates ``x``, ``y`` (x right, y
    down): ``xd, yd`` and the terms ``r2``, ``radial`` that :func:`_jacobian` needs."""
    k1, k2, p1, p2 = _coefficients(cam)
    r2 = x * x + y * y
    radial = 1.0 + k1 * r2 + k2 * r2 * r2
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + 2 * p2 * x * y + p1 * (r2 + 2 * y * y)
    return xd, yd, r2, radial


def _jacobian(cam: ColmapCamera, x, y, r2, radial):
    """∂x_d/∂x, ∂x_d/∂y, ∂y_d/∂x, ∂y_d/∂y of :func:`_distort` at ``x``, ``y``."""
    k1, k2, p1, p2 = _coefficients(cam)
    g = 2.0 * (k1 + 2.0 * k2 * r2)
    return (radial + g * x * x + 2 * p1 * y + 6 * p2 * x, g * x * y + 2 * p1 * x + 2 * p2 * y,
            g * x * y + 2 * p2 * y + 2 * p1 * x, radial + g * y * y + 2 * p2 * x + 6 * p1 * y)  # fmt: skip


#: Observations undistorted per batch (bounds the temporaries of the Newton iteration).
UNDISTORT_BATCH: int = 1 << 16


def normalised(cam: ColmapCamera, uv: NDArray[np.float64], source: str = "") -> NDArray[np.float64]:
    """Undistorted normalised coordinates (x right, y down) of pixel observations ``uv``.

    ``(u − cx)/fx, (v − cy)/fy`` with COLMAP's distortion (SIMPLE_RADIAL, RADIAL,
    OPENCV) inverted by Newton's method (analytic 2 × 2 Jacobian) to
    :data:`UNDISTORT_TOL_PX` (px), in batches of :data:`UNDISTORT_BATCH`; an observation
    that does not converge raises ``InputError`` (distortion too strong to invert there).
    """
    p = cam.named()
    fx, fy = p.get("fx", p.get("f")), p.get("fy", p.get("f"))
    out = np.empty_like(uv, dtype=float)
    distorted = any(_coefficients(cam))
    tol = UNDISTORT_TOL_PX / max(fx, fy)
    for a in range(0, len(out), UNDISTORT_BATCH):  # batches: temporaries stay in the cache
        dx = (uv[a : a + UNDISTORT_BATCH, 0] - p["cx"]) / fx
        dy = (uv[a : a + UNDISTORT_BATCH, 1] - p["cy"]) / fy
        if not distorted:
            out[a : a + UNDISTORT_BATCH, 0] = dx
            out[a : a + UNDISTORT_BATCH, 1] = dy
            continue
        x, y = _undistort(cam, dx, dy, tol)
        xd, yd, _, _ = _distort(cam, x, y)
        bad = np.flatnonzero(
            (np.abs(xd - dx) >= tol) | (np.abs(yd - dy) >= tol) | ~np.isfinite(x) | ~np.isfinite(y)
        )
        if bad.size:
            u = uv[a + bad[0]]
            raise InputError(
                f"{cam.model} camera: the lens distortion cannot be inverted at pixel "
                f"({u[0]:.1f}, {u[1]:.1f}) ({bad.size} observation(s))",
                source=source,
            )
        out[a : a + UNDISTORT_BATCH, 0] = x
        out[a : a + UNDISTORT_BATCH, 1] = y
    return out


def _undistort(cam: ColmapCamera, dx, dy, tol: float):
    """Newton's method for the normalised coordinates whose distortion is ``dx``, ``dy``.

    Starts at the distorted coordinates; an observation stops moving once its distortion
    is within ``tol`` of the target (at most 30 steps); the others are stepped on alone.
    """
    x, y = dx.copy(), dy.copy()
    at = np.arange(dx.size)  # the observations still moving, and their values
    ax, ay, tx, ty = x, y, dx, dy
    for _ in range(30):
        xd, yd, r2, radial = _distort(cam, ax, ay)
        fx_, fy_ = xd - tx, yd - ty
        done = (np.abs(fx_) < tol) & (np.abs(fy_) < tol)
        if done.all():
            break
        if done.any():
            go = ~done
            at, ax, ay, tx, ty = at[go], ax[go], ay[go], tx[go], ty[go]
            fx_, fy_, r2, radial = fx_[go], fy_[go], r2[go], radial[go]
        a11, a12, a21, a22 = _jacobian(cam, ax, ay, r2, radial)
        det = a11 * a22 - a12 * a21
        det = np.where(np.abs(det) < 1e-12, 1e-12, det)
        ax = ax - (a22 * fx_ - a12 * fy_) / det
        ay = ay - (-a21 * fx_ + a11 * fy_) / det
        x[at], y[at] = ax, ay
    return x, y
