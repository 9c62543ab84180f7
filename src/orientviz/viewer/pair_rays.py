"""Rays of one point of a stereo pair, their gap and the epipolar plane; normalised images.

Pure numpy (no viser, no drawing): :mod:`orientviz.viewer.pair_scene` draws what these
functions return. Frames as in :mod:`orientviz.orientation.plotter`: the left projector
at the origin with R = I, the right one at the base B = (b, by, bz) turned by the dials
(R₂ image → model); model frame X along the base, Y left, Z up, machine mm.

For a terrain point photographed in both images, the **left ray** is O₁ + t·d₁ with
d₁ = (x₁, y₁, −c) and the **right ray** O₂ + u·R₂ (x₂, y₂, −c). Unless the dials are
right the two rays miss each other: their **shortest connecting segment** is the gap the
relative orientation must close — its component across the base is the model's
y-parallax. The **epipolar plane** of the left ray holds O₁, O₂ and d₁; the right ray
lies in it exactly when the gap is zero (coplanarity).

The **normalised (epipolar) images** turn both bundles to one rotation whose x axis is the
base (:func:`orientviz.orientation.epipolar.normal_case_rotation`); there the epipolar
lines are image rows and the y-parallax of a point is y₁′ − y₂′.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..orientation.epipolar import normal_case_rotation, normalise_points
from ..orientation.relative import y_parallax
from ..rotation import matrix_from_opk
from .geometry import closest_points_of_rays

F64 = NDArray[np.float64]


def pair_frames(plotter: Any) -> tuple[F64, F64, F64, F64]:
    """Projection centres and rotations under the plotter's current dials.

    Returns
    -------
    O1, O2 : ndarray, shape (3,)
        Left and right projection centre, machine mm.
    R1, R2 : ndarray, shape (3, 3)
        Image → model rotations (R1 = I, R2 from the dials).
    """
    st = plotter.state
    R1 = matrix_from_opk(*st.angles_left, sequence=st.sequence)
    R2 = matrix_from_opk(*st.angles_right, sequence=st.sequence)
    return np.zeros(3), np.asarray(st.base, float), R1, R2


def point_rays(plotter: Any, point: ArrayLike, reach: float = 1.15) -> dict[str, Any]:
    """The two rays of one terrain point, their shortest segment and the left epipolar plane.

    Parameters
    ----------
    plotter : orientviz.orientation.plotter.AnalogPlotter
        The pair and its current dials.
    point : array_like, shape (3,)
        The true terrain point (machine mm); its image coordinates come from the
        photographs (:meth:`TruePair.images`), the rays from the current dials.
    reach : float
        The rays and the plane are drawn to ``reach`` × the depth of the closest points.

    Returns
    -------
    dict
        ``centres`` (2, 3); ``directions`` (2, 3) unit ray directions; ``rays`` (2, 2, 3)
        segments from each centre to beyond the point; ``closest`` (2, 3) the closest
        points on the left and the right ray; ``gap`` (3,) closest right − closest left
        (mm); ``gap_length`` (mm); ``p_y`` the plotter's y-parallax there (mm,
        Y_left − Y_right); ``plane`` (4, 3) the epipolar plane of the left ray as a
        parallelogram O₁, O₂, O₂ + t·d₁, O₁ + t·d₁; ``plane_normal`` (3,) unit, B × d₁;
        ``right_off_plane`` distance of the right ray's closest point from that plane
        (mm, signed along the normal).
    """
    P = np.asarray(point, dtype=float).reshape(1, 3)
    xy1, xy2 = plotter.pair.images(P)
    c = float(plotter.config.c)
    O1, O2, R1, R2 = pair_frames(plotter)
    d1 = R1 @ np.array([xy1[0, 0], xy1[0, 1], -c])
    d2 = R2 @ np.array([xy2[0, 0], xy2[0, 1], -c])
    d1, d2 = d1 / np.linalg.norm(d1), d2 / np.linalg.norm(d2)
    P1, P2 = closest_points_of_rays(O1, d1, O2, d2)
    P1, P2 = P1[0], P2[0]
    t1, t2 = float((P1 - O1) @ d1), float((P2 - O2) @ d2)
    B = O2 - O1
    n = np.cross(B, d1)
    n /= np.linalg.norm(n)
    t = reach * max(t1, t2)
    p_y, _ = y_parallax(xy1, xy2, c, plotter.state)
    return {
        "centres": np.array([O1, O2]),
        "directions": np.array([d1, d2]),
        "rays": np.array([[O1, O1 + reach * t1 * d1], [O2, O2 + reach * t2 * d2]]),
        "closest": np.array([P1, P2]),
        "gap": P2 - P1,
        "gap_length": float(np.linalg.norm(P2 - P1)),
        "p_y": float(p_y[0]),
        "plane": np.array([O1, O2, O2 + t * d1, O1 + t * d1]),
        "plane_normal": n,
        "right_off_plane": float((P2 - O1) @ n),
    }


def plane_mesh(corners: ArrayLike) -> tuple[F64, NDArray[np.uint32]]:
    """A flat quadrilateral (4, 3) as two triangles: vertices (4, 3) and faces (2, 3)."""
    V = np.asarray(corners, dtype=float).reshape(4, 3)
    return V, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32)


def normalised_pair(plotter: Any, points: ArrayLike) -> dict[str, Any]:
    """Image points of the pair re-projected into the normalised images (current dials).

    Parameters
    ----------
    plotter : orientviz.orientation.plotter.AnalogPlotter
    points : array_like, shape (n, 3)
        True terrain points, machine mm.

    Returns
    -------
    dict
        ``left``, ``right`` (n, 2) normalised image coordinates (mm, principal distance
        c); ``p_y`` (n,) y₁′ − y₂′ in image mm (zero for every point when the dials are
        right: the epipolar lines are the rows); ``R_n`` (3, 3) the common rotation;
        ``c`` (mm); ``half_format`` (mm) half the side of the photographs.
    """
    P = np.asarray(points, dtype=float).reshape(-1, 3)
    xy1, xy2 = plotter.pair.images(P)
    c = float(plotter.config.c)
    O1, O2, R1, R2 = pair_frames(plotter)
    Rn = normal_case_rotation(R1, R2, O2 - O1)
    left = normalise_points(xy1, R1, Rn, c)
    right = normalise_points(xy2, R2, Rn, c)
    return {
        "left": left,
        "right": right,
        "p_y": left[:, 1] - right[:, 1],
        "R_n": Rn,
        "c": c,
        "half_format": 0.5 * float(plotter.config.format_mm),
    }
