"""Epipolar lines and normalised images on error-free simulated pairs."""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.camera import project
from orientviz.errors import InputError
from orientviz.orientation.epipolar import (
    epipolar_distances,
    epipolar_lines,
    essential_matrix,
    normal_case_points,
    normal_case_rotation,
    normalise_points,
)
from orientviz.rotation import matrix_from_opk


def _pair(seed=0):
    rng = np.random.default_rng(seed)
    c = 152.0
    P = np.column_stack(
        [rng.uniform(-10, 100, 20), rng.uniform(-90, 90, 20), -c + rng.uniform(-15, 15, 20)]
    )
    B = np.array([92.0, 3.0, -2.0])
    R1, R2 = matrix_from_opk(0.01, -0.02, 0.015), matrix_from_opk(-0.02, 0.03, 0.04)
    return c, P, B, R1, R2, project(P, np.zeros(3), R1, c), project(P, B, R2, c)


def test_true_matches_lie_on_their_lines_and_wrong_ones_do_not():
    c, P, B, R1, R2, x1, x2 = _pair()
    E = essential_matrix(R1, R2, B)
    assert np.abs(epipolar_distances(E, x1, x2, c)).max() < 1e-10
    L = epipolar_lines(E, x1, c)
    np.testing.assert_allclose(np.hypot(L[:, 0], L[:, 1]), 1.0)
    # the distance is in mm: a match moved 0.1 mm along the line's normal is 0.1 mm off
    moved = x2 + 0.1 * L[:, :2]
    np.testing.assert_allclose(epipolar_distances(E, x1, moved, c), 0.1, atol=1e-10)
    # points deeper or closer on the same left ray project onto the same line
    for s in (0.5, 2.0):
        q = project(s * (P @ np.eye(3)), np.zeros(3), R1, c)  # same left image point
        np.testing.assert_allclose(q, x1, atol=1e-9)
        q2 = project(s * P, B, R2, c)
        np.testing.assert_allclose(np.sum(L[:, :2] * q2, axis=1) + L[:, 2], 0.0, atol=1e-9)


def test_normalised_images_have_no_y_parallax_and_give_the_points_back():
    c, P, B, R1, R2, x1, x2 = _pair(1)
    Rn = normal_case_rotation(R1, R2, B)
    np.testing.assert_allclose(Rn.T @ Rn, np.eye(3), atol=1e-12)
    assert np.linalg.det(Rn) == pytest.approx(1.0)
    n1, n2 = normalise_points(x1, R1, Rn, c), normalise_points(x2, R2, Rn, c)
    assert np.abs(n1[:, 1] - n2[:, 1]).max() < 1e-10
    Q = normal_case_points(n1, n2, c, float(np.linalg.norm(B)))
    np.testing.assert_allclose(Q @ Rn.T, P, atol=1e-9)


def test_looking_along_the_base_has_no_normal_case():
    R = matrix_from_opk(0.0, np.pi / 2, 0.0)  # camera z axis along X
    with pytest.raises(InputError, match="along the base"):
        normal_case_rotation(R, R, [1.0, 0.0, 0.0])
