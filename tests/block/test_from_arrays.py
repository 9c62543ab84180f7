"""Block.from_arrays: point roles as codes or words, ids numbered or given."""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.block import Block
from orientviz.errors import InputError


def _arrays(p: int = 4) -> dict:
    return dict(
        camera_c=[150.0],
        image_camera=[0, 0],
        X0=[[0.0, 0.0, 1000.0], [300.0, 0.0, 1000.0]],
        angles=np.zeros((2, 3)),
        xyz=np.arange(3.0 * p).reshape(p, 3),
        obs_image=[0, 1],
        obs_point=[0, 1],
        obs_xy=[[1.0, 2.0], [3.0, 4.0]],
    )


@pytest.mark.parametrize(
    "role",
    [
        np.array([0, 1, 2, 1], np.int8),
        [0, 1, 2, 1],
        np.array([0, 1, 2, 1], np.uint64),
        ["tie", "control", "check", "control"],
        [0.0, 1.0, 2.0, 1.0],
    ],
)
def test_roles_as_codes_or_words_give_the_same_block(role):
    b = Block.from_arrays(**_arrays(), role=role)
    np.testing.assert_array_equal(b.points.role, [0, 1, 2, 1])
    assert b.points.role.dtype == np.int8


@pytest.mark.parametrize("role", [[0, 1, 3, 0], [0, -1, 0, 0], [0, 300, 0, 0], [0, 1, 2]])
def test_roles_out_of_range_or_count_are_named(role):
    with pytest.raises(ValueError, match="point role"):
        Block.from_arrays(**_arrays(), role=np.array(role))


def test_numbered_ids_are_distinct_and_given_ones_are_checked():
    b = Block.from_arrays(**_arrays())
    assert b.points.ids == ["pt0", "pt1", "pt2", "pt3"] and b.images.ids == ["img0", "img1"]
    with pytest.raises(InputError, match="duplicate point id 'a'"):
        Block.from_arrays(**_arrays(), point_ids=["a", "b", "a", "c"])
    with pytest.raises(InputError, match="duplicate image id"):
        Block.from_arrays(**_arrays(), image_ids=["x", "x"])
