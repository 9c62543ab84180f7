"""Plain scene data of radar images for the viewer and the plots (no drawing here).

Every function returns dicts of numpy arrays in object metres (right-handed, Z up) so
that :mod:`orientviz.viewer` can draw them in viser and :mod:`orientviz.plot.radar` in
matplotlib. Stable keys (the "Radar scene data" contract, book/api/contracts.md):

``station_scene(image, name)`` →
    ``{"name", "station" (3,), "axis" (2, 3) segment along k, "reference" (2, 3)
    segment along the reference direction i, "axis_length" float}``
``sphere_scene(xy, image)`` →
    ``{"centre" (3,), "radii" (n,)}`` — the range spheres of the image points (4b)
``circle_scene(xy, image, n_vertices)`` →
    ``{"polylines" (n, v, 3), "centre" (3,), "radii" (n,), "normals" (n, 3)}`` — the
    projection circles: the great circles in which the azimuth planes (4c) cut the spheres
``trilateration_scene(points, ranges)`` →
    ``{"centres" (3, 3), "radii" (3,), "candidates" (2, 3), "discriminant" float}``
``residual_scene(points, xy_obs, image, scale)`` →
    ``{"points" (n, 3), "image_residuals" (n, 2), "segments" (n, 2, 3)}`` — residual
    vectors drawn at the object points in the plane ⟂ k, exaggerated by ``scale``
``pair_scene(xy1, image1, xy2, image2)`` →
    ``{"stations" (2, 3), "points" (n, 3), "circles1", "circles2" (n, v, 3),
    "radii1", "radii2" (n,), "weak" (n,) bool}``
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .diagnostics import pair_geometry
from .pair import intersect
from .ppi import RadarImage, check_points, plane_normal, project, projection_circle, sphere_radius
from .trilateration import trilaterate_three


def station_scene(
    image: RadarImage, name: str = "radar", axis_length: float = 5000.0
) -> dict[str, Any]:
    """The station with its rotation axis k and reference direction i (segments, m)."""
    X0 = np.asarray(image.X0, float)
    R = image.R
    return {
        "name": name,
        "station": X0,
        "axis": np.vstack([X0, X0 + axis_length * R[:, 2]]),
        "reference": np.vstack([X0, X0 + axis_length * R[:, 0]]),
        "axis_length": float(axis_length),
    }


def sphere_scene(xy: ArrayLike, image: RadarImage) -> dict[str, Any]:
    """Range spheres (4b) of the image points: common centre and radii (m)."""
    return {"centre": np.asarray(image.X0, float), "radii": sphere_radius(xy, image)}


def circle_scene(xy: ArrayLike, image: RadarImage, n_vertices: int = 73) -> dict[str, Any]:
    """Projection circles: sphere (4b) ∩ azimuth plane (4c), as closed polylines (m)."""
    centre, radii, poly = projection_circle(xy, image, n_vertices)
    return {
        "polylines": poly,
        "centre": centre[0] if len(centre) else np.asarray(image.X0, float),
        "radii": radii,
        "normals": plane_normal(xy, image),
    }


def trilateration_scene(points: ArrayLike, ranges: ArrayLike) -> dict[str, Any]:
    """Three spheres and both trilateration candidates (closed form)."""
    C = check_points(points)[:3]
    r = np.asarray(ranges, float)[:3]
    lo, hi, disc = trilaterate_three(C, r)
    return {"centres": C, "radii": r, "candidates": np.vstack([lo, hi]), "discriminant": disc}


def residual_scene(
    points: ArrayLike, xy_obs: ArrayLike, image: RadarImage, scale: float = 1000.0
) -> dict[str, Any]:
    """Image residuals v = x(computed) − x(observed) as object-space arrows.

    The image residual (image m) is turned into the plane ⟂ k with R and divided by m,
    then multiplied by ``scale`` so that sub-metre residuals become visible.
    """
    P = check_points(points)
    v = project(P, image) - np.asarray(xy_obs, float)
    v3 = np.column_stack([v, np.zeros(len(v))]) @ image.R.T / image.m
    return {
        "points": P,
        "image_residuals": v,
        "segments": np.stack([P, P + scale * v3], axis=1),
    }


def pair_scene(
    xy1: ArrayLike, image1: RadarImage, xy2: ArrayLike, image2: RadarImage, n_vertices: int = 73
) -> dict[str, Any]:
    """Both stations, the intersected points and both sets of projection circles."""
    X = intersect(xy1, image1, xy2, image2)
    c1, c2 = circle_scene(xy1, image1, n_vertices), circle_scene(xy2, image2, n_vertices)
    geo = pair_geometry(xy1, image1, xy2, image2, X)
    return {
        "stations": np.vstack([image1.X0, image2.X0]).astype(float),
        "points": X,
        "circles1": c1["polylines"],
        "circles2": c2["polylines"],
        "radii1": c1["radii"],
        "radii2": c2["radii"],
        "weak": geo.weak,
    }
