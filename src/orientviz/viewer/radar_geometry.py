"""Geier's construction of one radar image point, and the surfaces the radar scene shades.

Pure numpy (no viser): the radar scene (:mod:`orientviz.viewer.radar_scene`) draws what
these functions return, and the tests check them without a browser.

Geier (1973, Fig. 4) back-projects an image point with the image vector
``b = (x_B − x0, y_B − y0)`` by two surfaces through the station X0:

* the **range sphere** (4b) with the slant range s = sqrt((‖b‖/m)² + h²) as radius, and
* the **azimuth plane** (4c) that holds the antenna axis k and the direction R·b.

They meet in the **slant-range circle**, a great circle of the sphere; the object point
lies somewhere on it. The image itself keeps only the azimuth and the approximate
horizontal range s_e = ‖b‖/m = sqrt(s² − h²): it is the picture of the circle's point
in the **ground plane** of the model — the plane ⟂ k at the distance h from the station.
There the point lies s_e from the foot of the axis (X0 − h·k), and the triangle station
– foot – image point has the sides h, s_e and s (Pythagoras, Geier's reduction).

Units: object metres; angles in radians.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..radar.ppi import azimuth_direction, plane_normal, sphere_radius

F64 = NDArray[np.float64]
I32 = NDArray[np.int32]


def _basis(normal: F64) -> tuple[F64, F64]:
    """Two unit vectors that span the plane ⟂ ``normal`` (right-handed with it)."""
    n = normal / np.linalg.norm(normal)
    helper = np.array([0.0, 0.0, 1.0]) if abs(n[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    a = np.cross(n, helper)
    a /= np.linalg.norm(a)
    return a, np.cross(n, a)


def disc_mesh(centre: ArrayLike, normal: ArrayLike, radius: float, n: int = 72) -> tuple[F64, I32]:
    """A flat disc as a triangle fan.

    Parameters
    ----------
    centre : array_like, shape (3,)
        Centre in m.
    normal : array_like, shape (3,)
        Normal of the disc's plane (need not be unit length).
    radius : float
        Radius in m.
    n : int
        Number of rim vertices.

    Returns
    -------
    vertices : ndarray, shape (n + 1, 3)
        The centre first, then the rim.
    faces : ndarray of int32, shape (n, 3)
    """
    c = np.asarray(centre, dtype=float).reshape(3)
    a, b = _basis(np.asarray(normal, dtype=float).reshape(3))
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    rim = c + radius * (np.cos(t)[:, None] * a + np.sin(t)[:, None] * b)
    i = np.arange(n)
    faces = np.column_stack([np.zeros(n, int), 1 + i, 1 + (i + 1) % n]).astype(np.int32)
    return np.vstack([c, rim]), faces


def cap_mesh(
    centre: ArrayLike,
    radius: float,
    towards: ArrayLike,
    half_angle: float,
    n_rings: int = 16,
    n_seg: int = 64,
) -> tuple[F64, I32]:
    """The cap of a sphere around one direction, as a triangle mesh.

    A range sphere of 15-60 km dwarfs the scene; the cap around the station shows where
    the spheres cross without hiding the rest. ``half_angle = π`` gives the whole sphere.

    Parameters
    ----------
    centre : array_like, shape (3,)
        Sphere centre, m.
    radius : float
        Sphere radius, m.
    towards : array_like, shape (3,)
        Direction from the centre to the middle of the cap.
    half_angle : float
        Angular radius of the cap, rad (0 < half_angle ≤ π).
    n_rings, n_seg : int
        Rings of latitude and vertices per ring.

    Returns
    -------
    vertices : ndarray, shape (1 + n_rings·n_seg, 3)
        Every vertex at ``radius`` from ``centre``; the pole first.
    faces : ndarray of int32, shape (n_seg·(2·n_rings − 1), 3)
    """
    c = np.asarray(centre, dtype=float).reshape(3)
    w = np.asarray(towards, dtype=float).reshape(3)
    w = w / np.linalg.norm(w)
    a, b = _basis(w)
    theta = np.linspace(0.0, float(half_angle), n_rings + 1)[1:]
    phi = np.linspace(0.0, 2.0 * np.pi, n_seg, endpoint=False)
    st, ct = np.sin(theta)[:, None, None], np.cos(theta)[:, None, None]
    ring = ct * w + st * (np.cos(phi)[None, :, None] * a + np.sin(phi)[None, :, None] * b)
    verts = np.vstack([c + radius * w, (c + radius * ring).reshape(-1, 3)])
    j = np.arange(n_seg)
    fan = np.column_stack([np.zeros(n_seg, int), 1 + j, 1 + (j + 1) % n_seg])
    quads = []
    for r in range(n_rings - 1):
        p, q = 1 + r * n_seg, 1 + (r + 1) * n_seg
        quads.append(np.column_stack([p + j, q + j, q + (j + 1) % n_seg]))
        quads.append(np.column_stack([p + j, q + (j + 1) % n_seg, p + (j + 1) % n_seg]))
    return verts, np.vstack([fan, *quads]).astype(np.int32)


def arc(centre: ArrayLike, radius: float, e1: ArrayLike, e2: ArrayLike, t0: float, t1: float,
        n: int = 48) -> F64:  # fmt: skip
    """Points c + r (cos t e1 + sin t e2) for t from ``t0`` to ``t1`` (rad), shape (n, 3)."""
    t = np.linspace(float(t0), float(t1), n)[:, None]
    c = np.asarray(centre, dtype=float).reshape(3)
    return c + radius * (np.cos(t) * np.asarray(e1, float) + np.sin(t) * np.asarray(e2, float))


def geier_construction(point: ArrayLike, xy: ArrayLike, image: Any, n: int = 181) -> dict[str, Any]:
    """Geier's construction (Fig. 4) of one target in one radar image.

    Parameters
    ----------
    point : array_like, shape (3,)
        The target's object point, m (to draw the slant range and the arc).
    xy : array_like, shape (2,)
        Its image coordinates in the image, image m (rounded or exact).
    image : orientviz.radar.ppi.RadarImage
        The image's ten parameters.
    n : int
        Vertices of the circles.

    Returns
    -------
    dict
        ``station`` (3,); ``axis`` (3,) unit k; ``azimuth`` (3,) unit R·b/‖b‖;
        ``normal`` (3,) unit normal of the azimuth plane; ``s`` slant range (4b), ``s_e``
        approximate horizontal range ‖b‖/m, ``h`` (m); ``foot`` (3,) the foot of the
        axis in the ground plane, X0 − h·k on the target's side; ``image_point`` (3,)
        the image point in the ground plane, foot + s_e·azimuth (on the circle);
        ``circle`` (n, 3) closed slant-range circle; ``range_ring`` (n, 3) closed circle
        of radius s_e about the foot in the ground plane (every point at the same image
        distance from the principal point); ``arc`` (k, 3) along the circle from the
        target to the image point; ``elevation`` angle of the target above the plane
        ⟂ k (rad); ``gap`` distance of the target from the circle (m, 0 for exact
        image coordinates).
    """
    P = np.asarray(point, dtype=float).reshape(3)
    b = np.asarray(xy, dtype=float).reshape(1, 2)
    X0 = np.asarray(image.X0, dtype=float)
    k = np.asarray(image.axis, dtype=float)
    e = azimuth_direction(b, image)[0]
    s = float(sphere_radius(b, image)[0])
    h = float(image.h)
    s_e = float(np.sqrt(max(s * s - h * h, 0.0)))
    d = P - X0
    side = -1.0 if d @ k <= 0 else 1.0  # the ground plane lies on the target's side
    foot = X0 + side * h * k
    t_target = float(np.arctan2(d @ k, d @ e))
    t_image = float(np.arctan2(side * h, s_e))
    t = np.linspace(0.0, 2.0 * np.pi, n)
    circle = X0 + s * (np.cos(t)[:, None] * e + np.sin(t)[:, None] * k)
    a, c = _basis(k)
    ring = foot + s_e * (np.cos(t)[:, None] * a + np.sin(t)[:, None] * c)
    nrm = plane_normal(b, image)[0]
    d_in = d - (d @ nrm) * nrm  # the target's direction within the azimuth plane
    nearest = X0 + s * d_in / max(float(np.linalg.norm(d_in)), 1e-300)
    return {
        "station": X0,
        "axis": k,
        "azimuth": e,
        "normal": nrm,
        "s": s,
        "s_e": s_e,
        "h": h,
        "foot": foot,
        "image_point": foot + s_e * e,
        "circle": circle,
        "range_ring": ring,
        "arc": arc(X0, s, e, k, t_target, t_image),
        "elevation": t_target,
        "gap": float(np.linalg.norm(P - nearest)),
    }


def polyline_to_segments(points: ArrayLike) -> F64:
    """Consecutive points (n, 3) as line segments (n − 1, 2, 3)."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    return np.stack([p[:-1], p[1:]], axis=1)
