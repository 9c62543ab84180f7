"""Messages that fit the data: no aerial words for a hand-held (non-aerial) block."""

from __future__ import annotations

import numpy as np

import orientviz as ov
from orientviz.plausibility import check_block


def _behind_message(block):
    found = [f for f in check_block(block) if f.check == "behind"]
    assert found, "expected the points-behind finding"
    return found[0].message


def test_points_behind_an_aerial_camera_speak_of_heights():
    block = ov.simulate_block(1, 4, rng=3).block
    j = block.observations.point[block.points.role[block.observations.point] == 0][0]  # a tie
    block.points.xyz[j, 2] = block.images.X0[:, 2].max() + 100.0  # above the cameras
    assert "flying height" in _behind_message(block)


def test_points_behind_a_hand_held_camera_do_not():
    block = ov.simulate_block(1, 4, rng=3).block
    block.images.angles[:, 0] += np.pi / 2  # every camera looks horizontally
    k = np.flatnonzero(block.points.role[block.observations.point] == 0)[0]  # a tie point's ray
    i, j = block.observations.image[k], block.observations.point[k]
    block.points.xyz[j] = block.images.X0[i] + [0.0, -50.0, 0.0]  # behind image i
    msg = _behind_message(block)
    assert "flying height" not in msg and "heights" not in msg
    assert "check the angles of those images" in msg
