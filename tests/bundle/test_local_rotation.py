"""Rotation steps in the image frames from poor starts (orientviz.bundle.model._local_rotation)."""

from __future__ import annotations

import numpy as np
import pytest
from unordered_networks import close_range_network

import orientviz as ov
from orientviz.block import CONTROL
from orientviz.bundle import BundleOptions
from orientviz.bundle.model import apply_local, collinearity_block
from orientviz.orientation.intersection import intersect_rays
from orientviz.rotation import matrix_from_opk, matrix_from_rotvec, opk_from_matrix


def test_local_jacobian_matches_finite_differences_of_a_frame_rotation():
    block, _ = close_range_network(m=6, p=40)
    b = block
    args = (b.cameras.c[b.images.camera], np.zeros(6), np.zeros(6))
    obs = b.observations
    xyz = b.points.xyz[obs.point]
    f0, Je, _ = collinearity_block(b.images.X0, b.images.angles, *args, obs.image, xyz, local=True)
    h = 1e-7
    for k in range(3):
        d = np.zeros((6, 3))
        d[:, k] = h
        angles = apply_local(b.images.angles, d)
        f1, _, _ = collinearity_block(b.images.X0, angles, *args, obs.image, xyz)
        np.testing.assert_allclose((f1 - f0) / h, Je[:, :, 3 + k], rtol=1e-5, atol=1e-6)


def _poor_start(block, rng, angle_deg=20.0, shift=0.5):
    """Every image turned by ``angle_deg`` about a random axis and shifted; tie points
    intersected anew from the turned images (as benchmarks/bench_unordered.py does)."""
    b = block.copy()
    im, m = b.images, b.n_images
    axis = rng.normal(size=(m, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    R = matrix_from_opk(*im.angles.T) @ np.eye(3)
    R = matrix_from_rotvec(axis * np.radians(angle_deg)) @ R
    im.X0 += shift * rng.normal(size=(m, 3)) / np.sqrt(3)
    im.angles[:] = np.column_stack(opk_from_matrix(R)).reshape(-1, 3)
    ob = b.observations
    c = b.cameras.c[im.camera[ob.image]]
    d = np.einsum("nij,nj->ni", R[ob.image], np.column_stack([ob.xy, -c]))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    xyz, _ = intersect_rays(im.X0[ob.image], d, ob.point, b.points.xyz.shape[0])
    tie = b.points.role != CONTROL
    b.points.xyz[tie] = xyz[tie]
    return b


def test_poor_start_converges_to_the_optimum_with_fewer_steps():
    block, _ = close_range_network(m=16, p=150, seed=8)
    # the ring's images have φ up to ±81°: turned by 30°, some pass the gimbal lock of
    # ω-φ-κ at φ = ±90°
    good = ov.bundle_adjust(block, precision=False)
    poor = _poor_start(block, np.random.default_rng(3), angle_deg=30.0)
    local = ov.bundle_adjust(poor, precision=True, max_iter=60)
    assert local.converged
    d = local.exterior - good.exterior
    d[:, 3:] = (d[:, 3:] + np.pi) % (2 * np.pi) - np.pi  # angles: the same up to 2π
    np.testing.assert_allclose(d, 0, atol=1e-7)
    assert local.sigma0 == pytest.approx(good.sigma0, rel=1e-9)
    # the precision is the one of ω, φ, κ (the last steps are taken in the angles)
    ref = ov.bundle_adjust(block, precision=True)
    np.testing.assert_allclose(local.std(), ref.std(), rtol=1e-5)
    no_frames = BundleOptions(local_sigma0=np.inf)  # steps in ω, φ, κ only
    angles = ov.bundle_adjust(poor, precision=False, max_iter=60, options=no_frames)
    assert angles.converged
    assert local.iterations + 3 <= angles.iterations  # 6 against 10
