"""ray_parallax: the largest angle between a point's rays and their mean direction."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from orientviz.bundle.loop import ray_parallax


def _block(rng, n_images=6, n_points=40):
    """What ray_parallax reads of a block: which image sees which point."""
    obs = [(i, p) for p in range(n_points) for i in range(n_images) if rng.random() < 0.6]
    obs += [(0, p) for p in range(n_points) if all(q != p for _, q in obs)]  # every point seen
    image, point = np.array(obs).T
    return SimpleNamespace(
        observations=SimpleNamespace(image=image, point=point),
        n_images=n_images,
        n_points=n_points,
    )


def _by_add_at(block, X0, xyz):
    """The formula written with np.add.at, np.cross and np.maximum.at."""
    obs = block.observations
    d = xyz[obs.point] - X0[obs.image]
    with np.errstate(invalid="ignore", divide="ignore"):
        d /= np.linalg.norm(d, axis=1)[:, None]
        mean = np.zeros((block.n_points, 3))
        np.add.at(mean, obs.point, d)
        mean /= np.linalg.norm(mean, axis=1)[:, None]
        cos = np.clip(np.einsum("ij,ij->i", d, mean[obs.point]), -1.0, 1.0)
        ang = np.arctan2(np.linalg.norm(np.cross(d, mean[obs.point]), axis=1), cos)
    out = np.full(block.n_points, -np.inf)
    np.maximum.at(out, obs.point, np.nan_to_num(ang, nan=np.inf))
    out[np.bincount(obs.point, minlength=block.n_points) < 2] = np.nan
    return out


@pytest.mark.parametrize("seed", range(6))
def test_the_same_bits_as_the_formula_by_add_at_and_cross(seed):
    rng = np.random.default_rng(seed)
    b = _block(rng)
    scale = 10.0 ** rng.uniform(-3, 6)
    X0 = rng.normal(size=(b.n_images, 3)) * scale
    xyz = rng.normal(size=(b.n_points, 3)) * scale * 10.0 ** rng.uniform(-1, 4)
    xyz[:3] = X0[0]  # rays of length zero (no direction)
    xyz[3] = np.nan
    xyz[4] = X0[1] + 1e9 * scale * np.array([0.0, 0.0, 1.0])  # near infinity
    got, want = ray_parallax(b, X0, xyz), _by_add_at(b, X0, xyz)
    assert np.array_equal(got, want, equal_nan=True)
    assert np.isnan(got[np.bincount(b.observations.point, minlength=b.n_points) < 2]).all()
    assert np.isfinite(got).sum() > b.n_points // 2  # most points: a finite parallax


def test_parallel_rays_have_no_parallax_and_crossing_rays_their_half_angle():
    rng = np.random.default_rng(9)
    b = _block(rng, n_images=2, n_points=2)
    b.observations.image, b.observations.point = np.array([0, 1, 0, 1]), np.array([0, 0, 1, 1])
    X0 = np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    xyz = np.array([[0.0, 0.0, 1.0], [0.0, 1e12, 0.0]])
    par = ray_parallax(b, X0, xyz)
    assert par[0] == pytest.approx(np.pi / 4, rel=1e-15)  # rays 90° apart, 45° to their mean
    assert par[1] < 1e-11
