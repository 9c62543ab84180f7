"""The "trust" damping of the image blocks in the frame of the image's scene."""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.bundle.problem._damping import image_damping, scene_centres
from orientviz.rotation import matrix_from_opk


def _tau(X0, angles, c, sequence):
    """τ = Rᵀ(c − X0) of one image."""
    R = matrix_from_opk(angles[0], angles[1], angles[2], sequence)
    return R.T @ (c - X0)


def _numeric_T(X0, angles, c, sequence, h=1e-6):
    """dz/d(X0, ω, φ, κ) with z = (τ, ω, φ, κ), by central differences."""
    T = np.zeros((6, 6))
    x = np.r_[X0, angles]
    for j in range(6):
        e = np.zeros(6)
        e[j] = h
        tp, tm = _tau(*np.split(x + e, 2), c, sequence), _tau(*np.split(x - e, 2), c, sequence)
        T[:3, j] = (tp - tm) / (2 * h)
    T[3:, 3:] = np.eye(3)
    return T


@pytest.mark.parametrize("sequence", ["opk", "pok"])
def test_marquardt_damping_in_the_scene_frame(sequence):
    rng = np.random.default_rng(14)
    m = 4
    X0 = rng.normal(0, 50, (m, 3))
    angles = rng.uniform(-1.2, 1.2, (m, 3))
    c = X0 + rng.normal(0, 20, (m, 3))
    J = rng.normal(size=(m, 20, 6)) * [1, 1, 1, 30, 30, 30]
    U = J.transpose(0, 2, 1) @ J
    lam = 0.37
    out = U.copy()
    image_damping(out, lam, X0, angles, c, sequence)
    for i in range(m):
        T = _numeric_T(X0[i], angles[i], c[i], sequence)
        Uz = np.linalg.inv(T).T @ U[i] @ np.linalg.inv(T)  # U in z = (τ, angles)
        # Marquardt in z: Uz + λ diag(Uz), back in (X0, angles): Tᵀ (...) T
        want = T.T @ (Uz + lam * np.diag(np.diag(Uz))) @ T
        np.testing.assert_allclose(out[i], want, rtol=1e-7, atol=1e-7 * np.abs(want).max())
        # an image turned about its scene point c (τ fixed) is damped by its angles only
        dth = rng.normal(size=3) * 1e-3
        d = np.linalg.solve(T, np.r_[0.0, 0.0, 0.0, dth])
        pen = d @ (out[i] - U[i]) @ d
        assert pen == pytest.approx(lam * np.sum(np.diag(Uz)[3:] * dth**2), rel=1e-6)


def test_scene_centres_and_images_without_points():
    xyz = np.array([[0.0, 0, 0], [2, 0, 0], [0, 4, 0], [np.nan, 0, 0], [1e9, -1e9, 3e9]])
    image = np.array([3, 0, 0, 1, 1, 2, 3, 3])
    point = np.array([1, 0, 1, 2, 3, 3, 2, 4])
    X0 = np.arange(12.0).reshape(4, 3)
    c = scene_centres(image, point, xyz, X0)
    # the median per coordinate: image 3's far point (near infinity) does not move it
    np.testing.assert_array_equal(c, [[1, 0, 0], [0, 4, 0], X0[2], [2, 0, 0]])
