"""Small synthetic scenes for the lessons on rotations, absolute orientation and resection.

Everything is generated from explicit arguments and an ``rng`` (numpy Generator); units:
object coordinates in m, image coordinates in mm, angles in rad, R = R_ω R_φ R_κ.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..camera import project
from ..rotation import matrix_from_opk
from ..units import to_rad
from .absolute import SimilarityTransform

F64 = NDArray[np.float64]

#: Control layouts of :func:`similarity_example`: name → one-line description.
LAYOUTS: dict[str, str] = {
    "corners": "4 full XYZ points at the model corners",
    "minimal": "2 full XYZ points + 1 height point (7 coordinates, no redundancy)",
    "separate": "4 planimetric (XY) corners + 4 height (Z) points at the edge midpoints",
    "clustered": "4 full XYZ points crowded in one quarter of the model",
    "strip": "4 full XYZ points almost on one line along the base",
}


def house(width: float = 40.0, depth: float = 60.0, wall: float = 20.0, roof: float = 12.0):
    """A house wireframe standing on Z = 0, centred at the origin.

    Parameters
    ----------
    width, depth, wall, roof : float
        Extent along X and Y, wall height and ridge height above the walls, m.

    Returns
    -------
    points : ndarray, shape (10, 3)
        Corners in m.
    edges : ndarray of int, shape (17, 2)
        Index pairs of the wireframe.
    """
    w, d = width / 2, depth / 2
    base = np.array([[-w, -d], [w, -d], [w, d], [-w, d]])
    pts = np.vstack(
        [
            np.column_stack([base, np.zeros(4)]),
            np.column_stack([base, np.full(4, wall)]),
            [[0.0, -d, wall + roof], [0.0, d, wall + roof]],
        ]
    )
    edges = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4)]
    edges += [(0, 4), (1, 5), (2, 6), (3, 7), (4, 8), (5, 8), (6, 9), (7, 9), (8, 9)]
    return pts, np.array(edges)


def ground_grid(half: float = 300.0, n: int = 7) -> tuple[F64, NDArray[np.int64]]:
    """A flat n × n grid on Z = 0 (m) with its edges, for projected-image demos."""
    g = np.linspace(-half, half, n)
    X, Y = np.meshgrid(g, g, indexing="xy")
    pts = np.column_stack([X.ravel(), Y.ravel(), np.zeros(n * n)])
    idx = np.arange(n * n).reshape(n, n)
    edges = np.vstack(
        [
            np.column_stack([idx[:, :-1].ravel(), idx[:, 1:].ravel()]),
            np.column_stack([idx[:-1, :].ravel(), idx[1:, :].ravel()]),
        ]
    )
    return pts, edges


@dataclass
class SimilarityExample:
    """A model with control: ``source`` model coordinates, ``target`` control (NaN = not given).

    ``truth`` is the true transformation, ``target_true`` the error-free control.
    """

    source: F64
    target: F64
    target_true: F64
    truth: SimilarityTransform
    ids: list[str]
    layout: str


def similarity_example(
    layout: str = "corners", sigma: float = 0.05, *, rng: np.random.Generator
) -> SimilarityExample:
    """A relatively oriented model (~ 1:10 000 scale) and its control in one of :data:`LAYOUTS`.

    Parameters
    ----------
    layout : str, default "corners"
        A key of :data:`LAYOUTS`.
    sigma : float, default 0.05
        Standard deviation of the noise added to the control coordinates, m.
    rng : numpy.random.Generator
        Source of the noise.

    Returns
    -------
    SimilarityExample
        Model units are "model mm" (m / 10 000 · 1000), scale m = 10.
    """
    if layout not in LAYOUTS:
        raise ValueError(f"layout: expected one of {', '.join(LAYOUTS)}, got {layout!r}")
    truth = SimilarityTransform.from_params(
        [512_340.0, 5_402_110.0, 612.0, to_rad(0.8), to_rad(-1.3), to_rad(57.0), 10.0]
    )
    g = np.array([-100.0, 0.0, 100.0])  # model mm: a 2 km × 2 km model at scale 10
    pts = {
        "corners": [(-100, -100), (100, -100), (100, 100), (-100, 100)],
        "minimal": [(-100, -100), (100, 100), (100, -100)],
        "separate": [(-100, -100), (100, -100), (100, 100), (-100, 100)]
        + [(0, -100), (100, 0), (0, 100), (-100, 0)],
        "clustered": [(40, 40), (100, 40), (100, 100), (40, 100)],
        "strip": [(-100, -3), (-30, 4), (30, -4), (100, 3)],
    }[layout]
    xy = np.array(pts, dtype=float)
    # six extra model points without control (for the plot), on a 3 × 2 grid
    extra = np.array([(a, b) for a in g for b in (-50.0, 50.0)])
    allxy = np.vstack([xy, extra])
    z = 3.0 * np.sin(allxy[:, 0] / 40.0) + 2.0 * np.cos(allxy[:, 1] / 55.0)  # relief, model mm
    source = np.column_stack([allxy, z])
    target_true = truth.apply(source)
    target = target_true + rng.normal(0.0, sigma, target_true.shape)
    given = np.zeros(source.shape, bool)
    k = len(pts)
    given[:k] = True
    if layout == "minimal":
        given[2, :2] = False
    if layout == "separate":
        given[:4, 2] = False  # corners: planimetry only
        given[4:8, :2] = False  # edge midpoints: height only
    target = np.where(given, target, np.nan)
    ids = [f"P{i + 1}" for i in range(source.shape[0])]
    return SimilarityExample(source, target, target_true, truth, ids, layout)


@dataclass
class ResectionExample:
    """Control points and their (noisy) image coordinates for one near-vertical image."""

    object_points: F64
    image_points: F64
    X0: F64
    angles: F64
    c: float


def resection_example(
    n: int = 8,
    *,
    relief: float = 80.0,
    sigma: float = 0.005,
    height: float = 1500.0,
    c: float = 152.7,
    angles: tuple[float, float, float] = (0.02, -0.03, 1.2),
    rng: np.random.Generator,
) -> ResectionExample:
    """A near-vertical wide-angle image (c = 152.7 mm) over n control points.

    Parameters
    ----------
    n : int
        Number of control points (uniform over the image footprint).
    relief : float
        Height range of the control points, m.
    sigma : float
        Noise of the image coordinates, mm.
    height : float
        Flying height above the lowest ground, m.
    c : float
        Principal distance, mm.
    angles : tuple of float
        ω, φ, κ in rad (ω-φ-κ).
    rng : numpy.random.Generator

    Returns
    -------
    ResectionExample
    """
    half = 0.45 * 230.0 * height / c  # footprint half-width in m (mm × m/mm)
    X = np.column_stack(
        [rng.uniform(-half, half, n), rng.uniform(-half, half, n), rng.uniform(0, relief, n)]
    )
    X0 = np.array([15.0, -10.0, height])
    ang = np.asarray(angles, dtype=float)
    xy = project(X, X0, matrix_from_opk(*ang), c)
    return ResectionExample(X, xy + rng.normal(0.0, sigma, xy.shape), X0, ang, c)
