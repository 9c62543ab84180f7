"""Geometry of the radar panorama (PPI) image with approximate horizontal ranges.

After Geier (1973). A radar antenna turns about a fixed axis through the measuring
centre (the *station*) X0. For an object point X it records the plane azimuth of X about
the axis and the slant range s = ‖X − X0‖, reduced "by Pythagoras" with a constant
model parameter h to an *approximate horizontal range*

    s_e = sqrt(s² − h²).

Azimuth and s_e, times the image scale m, are plotted as plane polar coordinates about
the principal point (x0, y0). With the rotation R (image → object; its columns i, j, k
are the image axes in object space, k the antenna's rotation axis) and
(a, b, c) = Rᵀ (X − X0) the mapping equations (Geier's 4a) are::

    x_B = x0 + m · a · sqrt(1 + (c² − h²) / (a² + b²))  = x0 + m · s_e · a / sqrt(a² + b²)
    y_B = y0 + m · b · sqrt(1 + (c² − h²) / (a² + b²))  = y0 + m · s_e · b / sqrt(a² + b²)

Back-projection (4b, 4c): an image point (x_B, y_B) with the image vector
``bvec = (x_B − x0, y_B − y0, 0)`` lies on

* the *range sphere* about X0 with radius sqrt((‖bvec‖/m)² + h²) (4b; the paper writes
  ‖bvec‖² + h², i.e. bvec already reduced to object scale — here it is divided by m), and
* the *azimuth plane* through X0 containing the axis k and the direction R·bvec, with
  normal n = R (bvec × e_z) (4c).

Units: object coordinates, X0, h and image coordinates in metres; m dimensionless;
angles in radians. Rotation: ``R = R_φ · R_ω · R_κ`` (orientviz's ``"pok"`` sequence,
primary φ about Y, then ω about X, κ about the axis) — established from the paper's
numbers, see ``docs/geier_conventions.md``; the other sequence can be named.

The ten parameters of a single image, in this order everywhere in :mod:`orientviz.radar`:
``x0, y0, h, m, X0, Y0, Z0, phi, omega, kappa`` (:data:`PARAMS`). κ is the reference
direction of the antenna, the paper's α0 ("Verkantung") of the calibration.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputError
from ..rotation import SEQUENCES, check_sequence

F64 = NDArray[np.float64]

#: Names of the ten parameters of a radar panorama image, in vector order.
PARAMS: tuple[str, ...] = ("x0", "y0", "h", "m", "X0", "Y0", "Z0", "phi", "omega", "kappa")
#: The interior orientation (first four) and exterior orientation (last six).
INTERIOR: tuple[str, ...] = PARAMS[:4]
EXTERIOR: tuple[str, ...] = PARAMS[4:]
#: Default rotation sequence of the radar images (Geier 1973, see the conventions doc).
DEFAULT_SEQUENCE: str = "pok"


@dataclass(frozen=True)
class RadarImage:
    """The ten orientation parameters of one PPI image.

    Parameters
    ----------
    x0, y0 : float
        Principal point (image of the axis) in image metres.
    h : float
        Model parameter of the range reduction s_e = sqrt(s² − h²), in m.
    m : float
        Image scale (image metres per object metre of s_e).
    X0 : tuple of 3 floats
        Station (measuring centre) in object metres.
    phi, omega : float
        Tilts of the rotation axis in radians (about object Y and X).
    kappa : float
        Reference direction (α0) in radians, rotation about the axis.
    sequence : {"pok", "opk"}
        Rotation sequence: ``"pok"`` R = R_φ R_ω R_κ (default), ``"opk"`` R = R_ω R_φ R_κ.
    """

    x0: float
    y0: float
    h: float
    m: float
    X0: tuple[float, float, float]
    phi: float = 0.0
    omega: float = 0.0
    kappa: float = 0.0
    sequence: str = DEFAULT_SEQUENCE

    def __post_init__(self) -> None:
        check_sequence(self.sequence)
        v = self.vector()
        if not np.isfinite(v).all():
            raise InputError("expected finite radar image parameters, got NaN or inf")
        if self.m <= 0:
            raise InputError(f"expected an image scale m > 0, got {self.m}")

    def vector(self) -> F64:
        """The ten parameters as a vector in :data:`PARAMS` order (m, rad)."""
        return np.array(
            [self.x0, self.y0, self.h, self.m, *self.X0, self.phi, self.omega, self.kappa], float
        )

    @classmethod
    def from_vector(cls, p: ArrayLike, sequence: str = DEFAULT_SEQUENCE) -> RadarImage:
        """Build from a 10-vector in :data:`PARAMS` order (m, rad)."""
        p = np.asarray(p, dtype=float).reshape(-1)
        if p.shape != (10,):
            raise InputError(f"expected 10 radar parameters, got {p.shape[0]}")
        return cls(*p[:4], tuple(p[4:7]), *p[7:10], sequence=sequence)

    def with_(self, **changes) -> RadarImage:
        """A copy with some parameters changed."""
        return replace(self, **changes)

    @cached_property
    def R(self) -> F64:
        """Rotation matrix (image → object), columns i, j, k; k is the antenna axis
        (computed once per image, read-only)."""
        order = SEQUENCES[check_sequence(self.sequence)]
        ang = {0: self.omega, 1: self.phi, 2: self.kappa}
        E = [_elem(a, np.cos(ang[a]), np.sin(ang[a])) for a in order]
        return _read_only(E[0] @ E[1] @ E[2])

    @cached_property
    def _rotation_derivatives(self) -> tuple[F64, F64, F64]:
        """∂R/∂φ, ∂R/∂ω, ∂R/∂κ (same convention as :mod:`orientviz.rotation`; computed once
        per image, read-only)."""
        ang = {0: self.omega, 1: self.phi, 2: self.kappa}
        order = SEQUENCES[check_sequence(self.sequence)]
        cs = {a: (np.cos(ang[a]), np.sin(ang[a])) for a in order}
        E = [_elem(a, *cs[a]) for a in order]
        out = {}
        for pos, a in enumerate(order):
            f = list(E)
            f[pos] = _delem(a, *cs[a])
            out[a] = _read_only(f[0] @ f[1] @ f[2])
        return out[1], out[0], out[2]

    @property
    def axis(self) -> F64:
        """Unit vector of the rotation axis k in object space."""
        return self.R[:, 2]


def check_points(points: ArrayLike, name: str = "points") -> F64:
    """Return ``points`` as a float array of shape (n, 3) or raise :class:`InputError`."""
    P = np.asarray(points, dtype=float)
    if P.ndim == 1 and P.shape[0] == 3:
        P = P[None, :]
    if P.ndim != 2 or P.shape[1] != 3:
        raise InputError(f"expected {name} of shape (n, 3), got {P.shape}")
    if not np.isfinite(P).all():
        raise InputError(f"expected finite {name}, got NaN or inf")
    return P


def check_image_points(xy: ArrayLike, name: str = "image points") -> F64:
    """Return ``xy`` as a float array of shape (n, 2) or raise :class:`InputError`."""
    P = np.asarray(xy, dtype=float)
    if P.ndim == 1 and P.shape[0] == 2:
        P = P[None, :]
    if P.ndim != 2 or P.shape[1] != 2:
        raise InputError(f"expected {name} of shape (n, 2), got {P.shape}")
    if not np.isfinite(P).all():
        raise InputError(f"expected finite {name}, got NaN or inf")
    return P


def horizontal_range(points: ArrayLike, image: RadarImage) -> F64:
    """Approximate horizontal range s_e = sqrt(‖X − X0‖² − h²) in m, shape (n,).

    Raises
    ------
    InputError
        If a point is closer to the station than h (s_e imaginary: no image).
    """
    d = check_points(points) - np.asarray(image.X0, float)
    se2 = np.einsum("ij,ij->i", d, d) - image.h**2
    if np.any(se2 < 0):
        bad = np.flatnonzero(se2 < 0)
        raise InputError(
            f"points {bad.tolist()} are closer to the station than h = {image.h:g} m: no image"
        )
    return np.sqrt(se2)


def project(points: ArrayLike, image: RadarImage) -> F64:
    """Image coordinates (x_B, y_B) of object points, Geier's equations (4a).

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Object points in m.
    image : RadarImage
        The ten parameters.

    Returns
    -------
    ndarray, shape (n, 2)
        Image coordinates in image metres (not centred: the principal point is added).

    Raises
    ------
    InputError
        If a point lies on the axis (azimuth undefined) or within h of the station.
    """
    return project_with_jacobian(points, image, jacobian=False)[0]


def project_with_jacobian(
    points: ArrayLike, image: RadarImage, jacobian: bool = True, *, image_terms: bool = True
) -> tuple[F64, F64 | None, F64 | None]:
    """Image coordinates and their derivatives.

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Object points in m.
    image : RadarImage
        The ten parameters (rotation sequence included).
    jacobian : bool
        Compute the derivatives too.
    image_terms : bool
        With ``jacobian``, the derivatives by the image's parameters too (False: only
        those by the points; ``J_image`` is None).

    Returns
    -------
    xy : ndarray, shape (n, 2)
        Image coordinates in m.
    J_image : ndarray, shape (n, 2, 10) or None
        ∂(x_B, y_B)/∂(x0, y0, h, m, X0, Y0, Z0, φ, ω, κ): image m per m, per unit of m,
        per radian (None unless ``jacobian`` and ``image_terms``).
    J_points : ndarray, shape (n, 2, 3) or None
        ∂(x_B, y_B)/∂(X, Y, Z), image m per object m.
    """
    P = check_points(points)
    R = image.R
    d = P - np.asarray(image.X0, float)
    u = d @ R  # (a, b, c) = Rᵀ d
    a, b, c = u[:, 0], u[:, 1], u[:, 2]
    rho2 = a * a + b * b
    se2 = rho2 + c * c - image.h**2
    if (rho2 <= 0).any():
        raise InputError(
            f"points {np.flatnonzero(rho2 <= 0).tolist()} lie on the rotation axis: "
            "their azimuth is undefined"
        )
    if (se2 < 0).any():
        raise InputError(
            f"points {np.flatnonzero(se2 < 0).tolist()} are closer to the station than "
            f"h = {image.h:g} m: no image"
        )
    rho = np.sqrt(rho2)
    se = np.sqrt(se2)
    g = image.m * se / rho
    n = P.shape[0]
    xy = np.empty((n, 2))
    xy[:, 0] = image.x0 + g * a
    xy[:, 1] = image.y0 + g * b
    if not jacobian:
        return xy, None, None
    se_safe = np.where(se > 0, se, np.inf)
    # derivatives of g = m s_e / ρ
    t = image.m * (image.h**2 - c * c) / (se_safe * rho2 * rho)
    g_a, g_b = t * a, t * b
    g_c = image.m * c / (se_safe * rho)
    g_h = -image.m * image.h / (se_safe * rho)
    g_m = se / rho
    # ∂(x, y)/∂(a, b, c)
    Ju = np.empty((n, 2, 3))
    Ju[:, 0, 0] = g + a * g_a
    Ju[:, 0, 1] = a * g_b
    Ju[:, 0, 2] = a * g_c
    Ju[:, 1, 0] = b * g_a
    Ju[:, 1, 1] = g + b * g_b
    Ju[:, 1, 2] = b * g_c
    J_points = Ju @ R.T  # ∂u/∂X = Rᵀ
    if not image_terms:
        return xy, None, J_points
    Ji = np.zeros((n, 2, 10))
    Ji[:, 0, 0] = 1.0
    Ji[:, 1, 1] = 1.0
    Ji[:, 0, 2], Ji[:, 1, 2] = a * g_h, b * g_h
    Ji[:, 0, 3], Ji[:, 1, 3] = a * g_m, b * g_m
    Ji[:, :, 4:7] = -J_points
    for col, dR in zip((7, 8, 9), image._rotation_derivatives):
        Ji[:, :, col] = np.einsum("nij,nj->ni", Ju, d @ dR)
    return xy, Ji, J_points


def _elem(axis: int, c: float, s: float) -> F64:
    """3×3 elementary rotation (right-handed) about object axis 0/1/2 from cos, sin."""
    if axis == 0:
        return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    if axis == 1:
        return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _delem(axis: int, c: float, s: float) -> F64:
    if axis == 0:
        return np.array([[0.0, 0.0, 0.0], [0.0, -s, -c], [0.0, c, -s]])
    if axis == 1:
        return np.array([[-s, 0.0, c], [0.0, 0.0, 0.0], [-c, 0.0, -s]])
    return np.array([[-s, -c, 0.0], [c, -s, 0.0], [0.0, 0.0, 0.0]])


def _read_only(a: F64) -> F64:
    a.flags.writeable = False
    return a


def image_vector(xy: ArrayLike, image: RadarImage) -> F64:
    """Centred image vectors bvec = (x_B − x0, y_B − y0) in image m, shape (n, 2)."""
    return check_image_points(xy) - np.array([image.x0, image.y0])


def sphere_radius(xy: ArrayLike, image: RadarImage) -> F64:
    """Radius of the range sphere of each image point (4b): s = sqrt((‖bvec‖/m)² + h²), m."""
    bv = image_vector(xy, image) / image.m
    return np.sqrt(np.einsum("ij,ij->i", bv, bv) + image.h**2)


def plane_normal(xy: ArrayLike, image: RadarImage) -> F64:
    """Unit normals n = R (bvec × e_z)/‖…‖ of the azimuth planes (4c), shape (n, 3).

    The plane passes through the station X0 and contains the axis k and the object
    direction R·bvec; a point X lies on it when (X − X0)·n = 0.
    """
    bv = image_vector(xy, image)
    nloc = np.column_stack([bv[:, 1], -bv[:, 0], np.zeros(len(bv))])
    norm = np.linalg.norm(nloc, axis=1)
    if np.any(norm == 0):
        raise InputError("an image point at the principal point has no azimuth plane")
    return (nloc / norm[:, None]) @ image.R.T


def azimuth_direction(xy: ArrayLike, image: RadarImage) -> F64:
    """Unit vectors R·bvec/‖bvec‖ in object space (the azimuth in the plane ⟂ k), (n, 3)."""
    bv = image_vector(xy, image)
    loc = np.column_stack([bv, np.zeros(len(bv))])
    return (loc / np.linalg.norm(loc, axis=1)[:, None]) @ image.R.T


def projection_circle(
    xy: ArrayLike, image: RadarImage, n_vertices: int = 73
) -> tuple[F64, F64, F64]:
    """The circle in which the azimuth plane (4c) cuts the range sphere (4b).

    Returns
    -------
    centre : ndarray, shape (n, 3)
        The station X0 repeated (the circles are great circles of the spheres).
    radius : ndarray, shape (n,)
        Sphere radius in m.
    polyline : ndarray, shape (n, n_vertices, 3)
        Closed polylines of the circles in object metres.
    """
    r = sphere_radius(xy, image)
    e1 = azimuth_direction(xy, image)
    e2 = np.broadcast_to(image.axis, e1.shape)
    t = np.linspace(0.0, 2.0 * np.pi, n_vertices)
    ct, st = np.cos(t)[None, :, None], np.sin(t)[None, :, None]
    X0 = np.asarray(image.X0, float)
    poly = X0 + r[:, None, None] * (ct * e1[:, None, :] + st * e2[:, None, :])
    return np.broadcast_to(X0, (len(r), 3)).copy(), r, poly


def back_project(xy: ArrayLike, image: RadarImage, elevation: ArrayLike) -> F64:
    """Object point on the projection circle at a given angle from the plane ⟂ k.

    Parameters
    ----------
    xy : array_like, shape (n, 2)
        Image coordinates in m.
    image : RadarImage
    elevation : float or array_like, shape (n,)
        Angle (rad) between the azimuth direction and the station→point vector, positive
        towards +k. The single degree of freedom the image leaves open.

    Returns
    -------
    ndarray, shape (n, 3)
        Object points in m.
    """
    r = sphere_radius(xy, image)
    e1 = azimuth_direction(xy, image)
    el = np.broadcast_to(np.asarray(elevation, float), r.shape)
    return np.asarray(image.X0, float) + r[:, None] * (
        np.cos(el)[:, None] * e1 + np.sin(el)[:, None] * image.axis
    )


def tolerant(model, n_obs: int, n_par: int):
    """Wrap a model so that, after its first call, impossible geometry gives NaN.

    The first evaluation (at the approximations) raises :class:`InputError` as usual;
    later ones (during the iteration) return NaN observations instead, which the engine
    reports as "the observation equations became undefined" — a diverging iteration, not bad input.
    """
    state = {"first": True}

    def wrapped(u):
        if state["first"]:
            state["first"] = False
            return model(u)
        try:
            return model(u)
        except InputError:
            return np.full(n_obs, np.nan), np.zeros((n_obs, n_par))

    return wrapped
