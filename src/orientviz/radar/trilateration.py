"""Spatial trilateration ("räumlicher Bogenschnitt") of a radar station.

Only the station X0 acts radially: the radial image distance r = ‖bvec‖ of a point fixes
its slant range s = sqrt((r/m)² + h²) (equation 4b) and so a sphere about the point
that contains the station. Three spheres meet in two points (real, coincident or
imaginary); more spheres give a least-squares station.

* :func:`trilaterate_three` — closed form for three spheres, both candidates.
* :func:`sphere_ranges` — the slant ranges from the image (needs x0, y0, h, m).

Units: metres throughout.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError, NotDeterminableError
from .ppi import RadarImage, check_points, sphere_radius

F64 = NDArray[np.float64]

#: Relative size (against the largest centre distance) below which three centres
#: count as collinear.
COLLINEAR_TOLERANCE: float = 1e-9


def sphere_ranges(xy: ArrayLike, image: RadarImage) -> F64:
    """Slant ranges s = sqrt((‖bvec‖/m)² + h²) in m from image coordinates (4b)."""
    return sphere_radius(xy, image)


def trilaterate_three(centres: ArrayLike, radii: ArrayLike) -> tuple[F64, F64, float]:
    """Both points at given distances from three centres (closed form).

    Parameters
    ----------
    centres : array_like, shape (3, 3)
        Sphere centres (the object points) in m.
    radii : array_like, shape (3,)
        Sphere radii (slant ranges) in m.

    Returns
    -------
    below, above : ndarray, shape (3,)
        The two candidates, ordered by Z (``below`` has the smaller Z). When the
        spheres do not quite meet (the discriminant is slightly negative because of
        rounding), both are the point of closest approach.
    discriminant : float
        Squared distance of the candidates from the plane of the centres (m²); negative
        when the spheres have no common point.

    Raises
    ------
    NotDeterminableError
        If the three centres are (nearly) collinear: the spheres then meet in a circle
        about that line, the station's rotation about it is free.
    """
    C = check_points(centres, "sphere centres")
    r = np.asarray(radii, dtype=float).reshape(-1)
    if C.shape[0] != 3 or r.shape[0] != 3:
        raise InputError(f"expected 3 centres and 3 radii, got {C.shape[0]} and {r.shape[0]}")
    if np.any(r <= 0) or not np.all(np.isfinite(r)):
        raise InputError("expected positive finite sphere radii")
    e1 = C[1] - C[0]
    d = np.linalg.norm(e1)
    if d == 0:
        raise NotDeterminableError(
            "trilateration: two sphere centres coincide; X0, Y0, Z0 not determinable",
            ["X0", "Y0", "Z0"],
            1,
        )
    e1 = e1 / d
    w = C[2] - C[0]
    i = float(e1 @ w)
    e2 = w - i * e1
    j = np.linalg.norm(e2)
    scale = max(d, np.linalg.norm(w))
    if j <= COLLINEAR_TOLERANCE * scale:
        raise NotDeterminableError(
            "trilateration: the three points lie on one line, the spheres meet in a circle "
            "about it; the station's position on that circle (X0, Y0, Z0) is not determinable",
            ["X0", "Y0", "Z0"],
            1,
        )
    e2 = e2 / j
    e3 = np.cross(e1, e2)
    x = (r[0] ** 2 - r[1] ** 2 + d**2) / (2 * d)
    y = (r[0] ** 2 - r[2] ** 2 + i**2 + j**2) / (2 * j) - i * x / j
    disc = float(r[0] ** 2 - x**2 - y**2)
    z = np.sqrt(max(disc, 0.0))
    base = C[0] + x * e1 + y * e2
    p, q = base + z * e3, base - z * e3
    below, above = (p, q) if p[2] <= q[2] else (q, p)
    return below, above, disc
