"""A point that converged onto a camera that sees it is found and named (its ray has no
direction, so the precision fails there and the message says why)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from orientviz.bundle.loop._finish import AT_CENTRE, points_at_centres


def _block():
    X0 = np.array([[0.0, 0.0, 100.0], [50.0, 0.0, 100.0], [100.0, 0.0, 100.0]])
    xyz = np.array([[10.0, 5.0, 0.0], [60.0, -5.0, 0.0], [90.0, 8.0, 2.0], [40.0, 0.0, 1.0]])
    point = np.repeat(np.arange(4), 3)
    image = np.tile(np.arange(3), 4)
    obs = SimpleNamespace(point=point, image=image)
    return SimpleNamespace(observations=obs, n_points=4), X0, xyz


def test_only_a_point_at_its_own_camera_is_found():
    block, X0, xyz = _block()
    unknown = np.arange(4)
    assert points_at_centres(block, X0, xyz, unknown)[0].size == 0
    xyz[3] = X0[1] + [0.0, 0.0, 1e-8]  # onto image 1's centre (median ray ~100)
    point, image = points_at_centres(block, X0, xyz, unknown)
    assert point.tolist() == [3] and image.tolist() == [1]
    xyz[3] = X0[1] + [0.0, 0.0, 1e3 * AT_CENTRE * 100]  # near, but a ray with a direction
    assert points_at_centres(block, X0, xyz, unknown)[0].size == 0
    xyz[3] = X0[1]
    assert points_at_centres(block, X0, xyz, np.arange(3))[0].size == 0  # not an unknown
