"""The precision of a block with a point near infinity (``bundle.precision._far``).

A point whose rays meet at less than 1e-5 rad has no determined depth; formed with it,
the reduced system is not positive definite in floating point. The precision places such
a point along its mean ray where its rays meet at 1e-4 rad: checked against the textbook
inverse at that placement, and for not depending on where it is placed; at the given
values (``max_iter=0``: the precision of that state, where the point is far).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from test_reference import one_blas_thread, textbook_cofactors  # noqa: F401

import orientviz as ov
import orientviz.bundle.precision._far as far_module
from orientviz.block import Block
from orientviz.bundle.precision._far import HELD_PARALLAX, PLACED_PARALLAX
from orientviz.bundle.reference import reference_data
from orientviz.camera import project

#: the far point's distance from the block (m): its rays meet at ~1e-6 rad
FAR = 1e9


def _with_far_point(block: Block, images: list[int]) -> Block:
    """``block`` and one more tie point, ``FAR`` m below it, seen exactly by ``images``."""
    obs, img, pts, cam = block.observations, block.images, block.points, block.cameras
    far = img.X0.mean(axis=0) + FAR * np.array([0.01, -0.02, -1.0])
    R = block.rotations()[images]
    xy = project(np.tile(far, (len(images), 1)), img.X0[images], R, cam.c[img.camera[images]])
    p = block.n_points
    return Block.from_arrays(
        camera_c=cam.c, image_camera=img.camera, X0=img.X0, angles=img.angles,
        xyz=np.vstack([pts.xyz, far]), obs_image=np.r_[obs.image, images],
        obs_point=np.r_[obs.point, [p] * len(images)], obs_xy=np.vstack([obs.xy, xy]),
        obs_sigma=np.r_[obs.sigma, [obs.sigma[0]] * len(images)], role=np.r_[pts.role, 0],
        xyz_known=np.vstack([pts.xyz_known, [np.nan] * 3]),
        point_sigma=np.vstack([pts.sigma, [np.nan] * 3]), strip=img.strip,
        camera_format_mm=np.c_[cam.format_mm] if np.ndim(cam.format_mm) > 1 else cam.format_mm,
        sequence=block.sequence,
    )  # fmt: skip


@pytest.fixture(scope="module")
def far():
    """An aerial block (2 strips of 4 images) and a point 1e9 m below it in 3 images."""
    return _with_far_point(ov.simulate_block(2, 4, rng=3).block, [0, 1, 2])


def _placed_cofactors(block: Block, res) -> np.ndarray:
    """Q11 by the textbook formulae at ``res``'s state with the far point (the last) moved
    along its mean ray to where its rays meet at ``PLACED_PARALLAX``."""
    data = reference_data(block)
    j = block.n_points - 1
    centres = res.exterior[block.observations.image[block.observations.point == j], :3]
    d = res.points[j] - centres
    d = (d / np.linalg.norm(d, axis=1)[:, None]).sum(axis=0)
    centre = centres.mean(axis=0)
    spread = np.linalg.norm(centres - centre, axis=1).max()
    xyz = np.where(np.isfinite(res.points), res.points, block.points.xyz)
    xyz[j] = centre + spread / PLACED_PARALLAX * d / np.linalg.norm(d)
    state = SimpleNamespace(
        X0=res.exterior[:, :3], angles=res.exterior[:, 3:], xyz=xyz, ap=np.zeros(0)
    )
    return textbook_cofactors(data, state, block.sequence)[0]


def test_a_point_near_infinity_leaves_the_precision_of_the_rest(far, monkeypatch):
    res = ov.bundle_adjust(far, max_iter=0)  # the precision at the given values
    assert res.precision_error is None
    j = far.n_points - 1
    rays = far.observations.point == j
    d = res.points[j] - res.exterior[far.observations.image[rays], :3]
    d /= np.linalg.norm(d, axis=1)[:, None]
    assert np.linalg.norm(np.cross(d[0], d[1:]), axis=1).max() < HELD_PARALLAX  # near infinity
    Q = _placed_cofactors(far, res)
    m = far.n_images
    Qe = np.einsum("nii->ni", res.cofactor_groups["exterior"])
    np.testing.assert_allclose(Qe, np.diag(Q).reshape(m, 6), rtol=1e-7)
    # its depth is not determined: no cofactors, no point gains of its rays
    assert np.all(np.isnan(res.cofactor_groups["points"][j]))
    assert np.all(np.isnan(res.ray_gains.points[np.flatnonzero(rays)]))
    # the other points and the redundancy numbers are those of a finite computation
    tie = np.flatnonzero(far.points.role[:j] == 0)
    assert np.all(np.isfinite(res.cofactor_groups["points"][tie]))
    r = res.redundancy_numbers[: 2 * far.n_observations]
    assert np.all((r >= 0) & (r <= 1))
    # where it is placed hardly matters (its rays' directions are kept): ten times farther
    monkeypatch.setattr(far_module, "PLACED_PARALLAX", PLACED_PARALLAX / 10)
    farther = np.einsum("nii->ni", ov.bundle_adjust(far, max_iter=0).cofactor_groups["exterior"])
    assert np.max(np.abs(farther / Qe - 1)) < 1e-4
