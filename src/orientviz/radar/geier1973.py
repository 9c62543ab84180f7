"""The test data of Geier (1973), Fig. 7 and Fig. 8, as established from the numbers.

Fig. 7 gives 25 grid points (X, Y every 20 km, heights between −14 000 and −16 500 m)
and the parameters of three images with the same interior orientation:

1. the *normal case* ("Normalfall"): station at the origin, vertical axis, reference
   direction α0 = 0.1592 gon (the paper lists α0 next to the parameters of image 2),
2. the *near-normal case* ("genäherter Normalfall"): station (30 054.47, 28.16,
   −1 039.87), φ = 0.0955, ω = 0.1273, κ = 0.1592 gon,
3. the *general case*: station (25 043.17, 9 947.84, −472.16), φ = 6.1824,
   ω = 4.2365, κ = 17.5432 gon,

with approximations for the adjustments. The angles are in gon (printed with a degree
sign): 0.0955, 0.1273 and 0.1592 gon are 0.0015, 0.0020 and 0.0025 rad. The rotation is
R = R_φ R_ω R_κ (φ-ω-κ, κ about the antenna axis = α0 of the calibration). Both were
established by reproducing the paper's calibration numbers (docs/geier_conventions.md).

The surfaces of Fig. 8 replace the heights of the grid, keeping X and Y
(:data:`SURFACES`, columns 1-10): the Fig. 7 heights; the plane Z = −15 500 m (the mean
height); spheres and cylinders of radius 150 km and 300 km about the grid centre
(X = 15 000, Y = 0) — convex ones with their top at −15 500 m, concave ones with their
bottom at −17 000 m. "Zyl. x" is a cylinder whose axis runs in X (height varies with Y),
"Zyl. y" one whose axis runs in Y. Image coordinates are computed without error, then
rounded to whole metres.

Units: metres; angles in radians inside (the constants in gon are converted).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError
from ..units import to_rad
from .ppi import RadarImage, project

F64 = NDArray[np.float64]

#: Grid X and Y (m): five columns X = −25 000 … 55 000, five rows Y = 40 000 … −40 000.
GRID_X: tuple[float, ...] = (-25000.0, -5000.0, 15000.0, 35000.0, 55000.0)
GRID_Y: tuple[float, ...] = (40000.0, 20000.0, 0.0, -20000.0, -40000.0)
#: Heights Z of points 1-25 in Fig. 7 (m).
FIG7_Z: tuple[float, ...] = (
    -15000, -16500, -14500, -16000, -15500,
    -15500, -14000, -14500, -16500, -16500,
    -15500, -16000, -15500, -15500, -14500,
    -15500, -16500, -16000, -16000, -15500,
    -14000, -14000, -16500, -15500, -16500,
)  # fmt: skip
#: Centre of the grid, about which the curved surfaces of Fig. 8 are laid (m).
CENTRE_XY: tuple[float, float] = (15000.0, 0.0)
#: Height of the plane and of the top of the convex surfaces (m; the mean of Fig. 7).
PLANE_Z: float = -15500.0
#: Height of the bottom of the concave surfaces (m).
CONCAVE_BOTTOM_Z: float = -17000.0

#: Fig. 8 columns: key → (paper's heading, kind, radius m, convex?)
SURFACES: dict[str, tuple[str, str, float, bool]] = {
    "fig7": ("Willk. Höhen Fig. 7", "fig7", 0.0, False),
    "plane": ("Ebene", "plane", 0.0, False),
    "sphere150_convex": ("Kugel 150 (convex)", "sphere", 150e3, True),
    "cyl_y150_convex": ("Zyl. y 150 (convex)", "cyl_y", 150e3, True),
    "cyl_x150_convex": ("Zyl. x 150 (convex)", "cyl_x", 150e3, True),
    "sphere150_concave": ("Kugel 150 (concave)", "sphere", 150e3, False),
    "cyl_y150_concave": ("Zyl. y 150 (concave)", "cyl_y", 150e3, False),
    "cyl_x150_concave": ("Zyl. x 150 (concave)", "cyl_x", 150e3, False),
    "sphere300_concave": ("Kugel 300 (concave)", "sphere", 300e3, False),
    "cyl_x300_concave": ("Zyl. x 300 (concave)", "cyl_x", 300e3, False),
}
#: Column order of Fig. 8.
COLUMNS: tuple[str, ...] = tuple(SURFACES)

_GON = {
    "alpha0": 0.1592,
    "phi2": 0.0955,
    "omega2": 0.1273,
    "kappa2": 0.1592,
    "phi3": 6.1824,
    "omega3": 4.2365,
    "kappa3": 17.5432,
}


def grid_xy() -> F64:
    """X, Y of the 25 grid points in Fig. 7 order (row by row from Y = +40 km), m (25, 2)."""
    X, Y = np.meshgrid(GRID_X, GRID_Y)
    return np.column_stack([X.ravel(), Y.ravel()])


def surface_heights(name: str) -> F64:
    """Heights Z (m) of the 25 grid points on one of the Fig. 8 surfaces (:data:`SURFACES`)."""
    if name not in SURFACES:
        raise InputError(f"unknown surface {name!r}; expected one of {', '.join(SURFACES)}")
    _, kind, R, convex = SURFACES[name]
    xy = grid_xy()
    if kind == "fig7":
        return np.array(FIG7_Z, float)
    if kind == "plane":
        return np.full(25, PLANE_Z)
    dx, dy = xy[:, 0] - CENTRE_XY[0], xy[:, 1] - CENTRE_XY[1]
    r2 = {"sphere": dx**2 + dy**2, "cyl_x": dy**2, "cyl_y": dx**2}[kind]
    sag = R - np.sqrt(R**2 - r2)
    return PLANE_Z - sag if convex else CONCAVE_BOTTOM_Z + sag


def points(name: str = "fig7") -> F64:
    """The 25 object points (m, shape (25, 3)) on surface ``name``."""
    return np.column_stack([grid_xy(), surface_heights(name)])


def interior() -> dict[str, float]:
    """True interior orientation, the same for all three images (m; m dimensionless)."""
    return {"x0": 434.17, "y0": 716.82, "h": 15018.64, "m": 1.12637}


def images(sequence: str = "pok") -> dict[int, RadarImage]:
    """The true images 1 (normal), 2 (near-normal) and 3 (general case) of Fig. 7."""
    io = interior()
    g = {k: to_rad(v, "gon") for k, v in _GON.items()}
    return {
        1: RadarImage(**io, X0=(0.0, 0.0, 0.0), kappa=g["alpha0"], sequence=sequence),
        2: RadarImage(
            **io,
            X0=(30054.47, 28.16, -1039.87),
            phi=g["phi2"],
            omega=g["omega2"],
            kappa=g["kappa2"],
            sequence=sequence,
        ),
        3: RadarImage(
            **io,
            X0=(25043.17, 9947.84, -472.16),
            phi=g["phi3"],
            omega=g["omega3"],
            kappa=g["kappa3"],
            sequence=sequence,
        ),
    }


def approximations(sequence: str = "pok") -> dict[int, RadarImage]:
    """The approximations of Fig. 7 (index N) for images 2 and 3.

    Interior: x0N, y0N, hN, mN (calibration and the joint ten-parameter adjustment);
    exterior: the stations and rotations listed with index N (φN = ωN = κN = 0 for
    image 2). The calibration starts its reference direction α0 (= κ) from
    α0N = 0.3 gon instead, :func:`alpha0_approx`.
    """
    io = {"x0": 400.0, "y0": 700.0, "h": 15000.0, "m": 1.125}
    return {
        2: RadarImage(**io, X0=(30000.0, 0.0, -1000.0), sequence=sequence),
        3: RadarImage(
            **io,
            X0=(25000.0, 10000.0, -500.0),
            phi=to_rad(6.1, "gon"),
            omega=to_rad(4.2, "gon"),
            kappa=to_rad(17.5, "gon"),
            sequence=sequence,
        ),
    }


def alpha0_approx() -> float:
    """α0N = 0.3 gon, the calibration's approximation of the reference direction (rad)."""
    return to_rad(0.3, "gon")


def image_coordinates(name: str, image: int, *, rounded: bool = True, sequence: str = "pok") -> F64:
    """Image coordinates (m, (25, 2)) of surface ``name`` in image 1, 2 or 3.

    ``rounded=True`` rounds them to the nearest whole metre as the paper did (no exact
    value of image 2 lies within 0.5 mm of a half metre; images 1 and 3 have a few within
    0.07-0.7 mm, see docs/geier_conventions.md).
    """
    if image not in (1, 2, 3):
        raise InputError(f"expected image 1, 2 or 3, got {image!r}")
    xy = project(points(name), images(sequence)[image])
    return np.round(xy) if rounded else xy
