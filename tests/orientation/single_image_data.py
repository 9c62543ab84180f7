"""Synthetic single-image geometry shared by the resection and intersection tests."""

from __future__ import annotations

import numpy as np

import orientviz as ov

C_MM = 152.7


def ground_points(rng, n, relief=80.0):
    """n object points in a 1 km square with ``relief`` m of height differences."""
    return np.column_stack(
        [rng.uniform(-500, 500, n), rng.uniform(-500, 500, n), rng.uniform(0, relief, n)]
    )


def vertical_image():
    """A near-vertical image 1500 m above ground: (X0 m, angles rad, R)."""
    X0 = np.array([30.0, -20.0, 1500.0])
    ang = np.array([0.02, -0.03, 1.2])
    return X0, ang, ov.matrix_from_opk(*ang)
