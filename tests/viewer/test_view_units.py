"""A reconstruction is shown in its own units and at its own scale (issue 28 pt 6/7).

A close-range "object on a turntable" built here: 16 cameras on a ring of radius 3.5
(model units) around a 0.8-wide object, in a frame whose up is +Y (as a COLMAP model's
frame points anywhere), with exact pixel observations. Its scene must frame the cameras
and the object, draw frustums that are neither dots nor larger than the ring's spacing,
and its panel must speak of model units, degrees and pixels — never of m, gon or µm.
The aerial blocks keep their scale and words (checked on a simulated block).
"""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.io.problem import Units
from orientviz.rotation import opk_from_matrix
from orientviz.viewer.block_geometry import FRUSTUM_MIN, BlockGeometry
from orientviz.viewer.geometry import VIEW_FOV, VISIBLE_WIDTH
from orientviz.viewer.panel import position_span
from orientviz.viewer.state import BlockState
from orientviz.viewer.view_units import ViewUnits

PIXEL_MM = 0.01
#: a COLMAP-like import: model units, pixels, degrees
SFM = ViewUnits.of(Units("model", "deg", "px", PIXEL_MM))


def _turntable(radius: float = 3.5, n: int = 16) -> ov.Block:
    rng = np.random.default_rng(7)
    pts = rng.uniform(-0.4, 0.4, (1500, 3))  # cameras ~1 % of the positions, as in SfM
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    # the ring lies in the X-Z plane, 1 unit above the object along +Y ("up")
    X0 = np.column_stack([radius * np.cos(t), np.full(n, 1.0), radius * np.sin(t)])
    R = []
    for x in X0:
        back = x / np.linalg.norm(x)  # image +z: away from the object (looks along −z)
        right = np.cross([0.0, 1.0, 0.0], back)
        right /= np.linalg.norm(right)
        R.append(np.column_stack([right, np.cross(back, right), back]))  # image y ≈ up
    R = np.array(R)
    angles = np.column_stack(opk_from_matrix(R))
    c = 4000 * PIXEL_MM  # 4000 px
    obs_i, obs_p = np.divmod(np.arange(n * len(pts)), len(pts))
    local = np.einsum("nji,nj->ni", R[obs_i], pts[obs_p] - X0[obs_i])
    xy = -c * local[:, :2] / local[:, 2:3]
    return ov.Block.from_arrays(
        camera_c=[c], image_camera=np.zeros(n, int), X0=X0, angles=angles, xyz=pts,
        obs_image=obs_i, obs_point=obs_p, obs_xy=xy, obs_sigma=PIXEL_MM,
        camera_format_mm=(60.0, 40.0),
    )  # fmt: skip


@pytest.fixture(scope="module")
def turntable():
    return BlockGeometry(BlockState(_turntable(), units=SFM))


def test_a_reconstruction_has_its_own_up_and_scale(turntable):
    geo = turntable
    assert not geo.aerial  # model units: its Z is not up
    np.testing.assert_allclose(geo.up, [0.0, 1.0, 0.0], atol=1e-12)  # the images' y axes
    assert geo.height == pytest.approx(3.5, rel=0.15)  # the points' depth along the axes
    ring_spacing = 2 * 3.5 * np.sin(np.pi / 16)  # neighbouring cameras, 1.37 units
    assert FRUSTUM_MIN * geo.frame.size <= geo.frustum_depth <= 0.6 * ring_spacing + 1e-12


def test_the_first_view_frames_the_cameras_and_the_object(turntable):
    geo = turntable
    pos, look = geo.default_camera()
    b = geo.state.block
    axis = (look - pos) / np.linalg.norm(look - pos)
    right = np.cross(axis, geo.up)
    right /= np.linalg.norm(right)
    screen_up = np.cross(right, axis)
    # the window left of the panel (1280 × 800 px, the panel on the right 28 %)
    t = np.tan(VIEW_FOV / 2)
    d = geo.frame.to_scene(np.vstack([b.images.X0, b.points.xyz])) - pos
    x, y = (d @ right) / (d @ axis), (d @ screen_up) / (d @ axis)
    assert np.all(np.abs(y) < t) and np.all(y > -t)  # every camera and point in view
    assert np.all(x > -1.6 * t) and np.all(x < 1.6 * t * (2 * VISIBLE_WIDTH - 1))
    assert np.ptp(y) > 0.5 * t  # and not lost in a corner
    assert axis @ [0.0, 1.0, 0.0] < -0.3  # looking down (the frame's up is +Y) onto the ring


def test_a_reconstruction_is_named_in_model_units_pixels_and_degrees(turntable):
    seg, _, text = turntable.scale_bar(10.0)
    assert " model units at the object ≈ " in text and text.endswith(" px in the image")
    assert " m " not in text and "µm" not in text
    span, step = position_span(turntable.height, SFM.arbitrary_scale)
    assert (span, step) == (0.1, 0.001)  # 3 % of 3.5 units, no 1 m floor
    assert SFM.length_name == "model units" and SFM.angle == "deg"
    assert SFM.image_text(0.05) == "5 px" and ViewUnits().image_text(0.05) == "50 µm"


def test_an_aerial_block_keeps_its_heights_and_metres():
    sim = ov.simulate_block(2, 5, rng=3)
    geo = BlockGeometry(BlockState(sim.block))
    b = sim.block
    assert geo.aerial and np.array_equal(geo.up, [0.0, 0.0, 1.0])
    H = float(np.median(b.images.X0[:, 2]) - np.median(b.points.xyz[:, 2]))
    assert geo.height == H  # the flying height above the points, as before
    assert (
        " m at the object ≈ " in geo.scale_bar(10.0)[2]
        or " cm at the object" in (geo.scale_bar(10.0)[2])
    )
    assert position_span(geo.height)[1] == 0.1


def test_a_drone_model_without_scale_looks_down_its_own_up():
    """A nadir block flown back and forth, turned into an arbitrary frame and read in
    model units (a drone survey imported from COLMAP without control): its images' y axes
    cancel, so up is against their common viewing direction — the turned Z."""
    from orientviz.rotation import matrix_from_rotvec

    b = ov.simulate_block(2, 5, rng=3).block
    Q = matrix_from_rotvec(np.array([0.4, -1.1, 0.7]))  # object frame → an arbitrary one
    R = np.einsum("ij,njk->nik", Q, b.rotations())
    b.images.X0 = b.images.X0 @ Q.T
    b.points.xyz = b.points.xyz @ Q.T
    b.images.angles = np.column_stack(opk_from_matrix(R))
    assert np.linalg.norm(R[:, :, 1].mean(axis=0)) < 0.3  # strips back and forth
    geo = BlockGeometry(BlockState(b, units=SFM))
    assert not geo.aerial
    np.testing.assert_allclose(geo.up, Q @ [0.0, 0.0, 1.0], atol=0.05)
