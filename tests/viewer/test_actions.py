"""Acting on the adjustment from the viewer: switch, move, weight; undo and rewind.

State level (no viser) and through the panel's handlers on a local viser server
(127.0.0.1, ephemeral port), the way a click would call them.
"""

from dataclasses import replace

import numpy as np
import pytest

import orientviz as ov
from orientviz.viewer.edits import Edits, effective_block
from orientviz.viewer.state import BlockState


@pytest.fixture
def state():
    """A simulated 2 × 5 block (224 points, 4 control points), adjusted."""
    st = BlockState(ov.simulate_block(2, 5, rng=3).block)
    st.run()
    st.record("adjusted")
    return st


def same_state(st, change):
    """The state equals a recorded change exactly (arrays bit for bit, the same result)."""
    b = st.block
    np.testing.assert_array_equal(b.images.X0, change.X0)
    np.testing.assert_array_equal(b.images.angles, change.angles)
    np.testing.assert_array_equal(b.points.xyz, change.xyz)
    assert st.edits.equals(change.edits)
    assert st.result is change.result


def test_toggle_observation_resolves_and_undo_restores_exactly(state):
    st = state
    before = st.changes[st.change_cursor]
    s0 = st.result.sigma0
    j = 5
    c = st.toggle_observation(j)
    assert not st.edits.obs_on[j] and "off" in c.label
    assert st.result.redundancy == before.result.redundancy - 2
    assert np.isnan(st.result.normalized_residuals[2 * j : 2 * j + 2]).all()
    assert np.isfinite(st.result.residuals[2 * j])  # predicted from the orientations
    assert st.result.sigma0 != s0 and c.sigma0 == st.result.sigma0
    assert st.result.iterations <= 3  # warm start from the adjusted state
    assert not np.array_equal(st.block.points.xyz, before.xyz)
    st.undo()
    same_state(st, before)
    st.toggle_observation(j)
    st.toggle_observation(j)  # on again: the same solution as before (to the tolerance)
    np.testing.assert_allclose(st.block.points.xyz, before.xyz, atol=1e-6)


def test_toggle_image_leaves_it_out(state):
    st = state
    X0 = st.block.images.X0[1].copy()
    st.toggle_image(1)  # the middle image of strip 0 (a corner image would leave a defect)
    o = st.block.observations
    r = st.result.redundancy_numbers[: 2 * o.image.size].reshape(-1, 2)
    used = st.result.used_obs
    assert np.isnan(r[o.image == 1]).all() and not used[o.image == 1].any()
    assert np.isfinite(r[used]).all() and used[o.image == 0].sum() >= 7
    # points seen only by image 1 and one other image are left out, and said so
    assert (
        st.mapping.dropped_points.size
        and not used[np.isin(o.point, st.mapping.dropped_points)].any()
    )
    np.testing.assert_array_equal(st.block.images.X0[1], X0)  # not adjusted, kept
    assert np.isnan(st.result.cofactor_groups["exterior"][1]).all()
    assert st.mapping.images.tolist() == [0] + list(range(2, st.block.n_images))
    st.toggle_image(1)
    assert st.mapping.images.size == st.block.n_images


def test_control_off_becomes_check_point_and_move_shifts_the_block(state):
    st = state
    k = int(np.flatnonzero(st.block.points.role == 1)[0])
    st.toggle_control(k)
    chk = st.result.check_points
    assert chk is not None and st.block.points.ids[k] in list(chk.ids)
    st.toggle_control(k)
    before = st.changes[st.change_cursor]
    st.move_control(k, st.edits.known[k] + [0.5, 0.0, 0.0])
    assert st.edits.known[k, 0] == before.edits.known[k, 0] + 0.5
    np.testing.assert_allclose(st.block.points.xyz[k], st.edits.known[k])  # fixed control
    assert st.block.points.xyz[k + 1, 0] != before.xyz[k + 1, 0]  # its neighbours follow
    st.undo()
    same_state(st, before)


def test_weight_changes_sigma_and_failure_restores(state):
    st = state
    st.set_weight(7, 0.01)  # σ × 10
    np.testing.assert_allclose(st.result.sigma_obs[14:16], 10 * st.block.observations.sigma[7])
    before = st.changes[st.change_cursor]
    ctrl = np.flatnonzero(st.block.points.role == 1)
    st.toggle_control(int(ctrl[0]))
    n = len(st.changes)
    with pytest.raises(ov.OrientvizError):  # two of four control points off: datum defect
        st.toggle_control(int(ctrl[1]))
    assert len(st.changes) == n
    same_state(st, st.changes[-1])
    st.rewind(st.changes.index(before))
    same_state(st, before)


def test_rewind_returns_to_an_earlier_sigma0(state):
    st = state
    st.toggle_observation(3)
    st.toggle_observation(9)
    st.set_weight(11, 4.0)
    sig = [c.sigma0 for c in st.changes]
    assert len(set(sig[1:])) == len(sig) - 1  # every change changed σ̂0
    st.rewind(2)
    assert st.result.sigma0 == sig[2] and st.change_cursor == 2
    same_state(st, st.changes[2])
    st.rewind(4)  # forward again: nothing was lost
    same_state(st, st.changes[4])
    st.rewind(1)
    st.toggle_image(0)  # a new change after a rewind discards the later ones
    assert len(st.changes) == 3 and st.change_cursor == 2


def test_effective_block_drops_what_cannot_be_determined(block):
    e = Edits.of(block)
    o = block.observations
    tie = int(np.flatnonzero(block.points.role == 0)[0])
    rays = np.flatnonzero(o.point == tie)
    e.obs_on[rays[1:]] = False  # one ray left: the point leaves
    sub, mp = effective_block(block, e)
    assert tie not in mp.points and tie in mp.dropped_points
    assert sub.n_observations == block.n_observations - rays.size
    e = Edits.of(block)
    e.obs_on[np.flatnonzero(o.image == 4)[3:]] = False  # three rays left: still in
    assert 4 in effective_block(block, e)[1].images
    e.obs_on[np.flatnonzero(o.image == 4)[2]] = False  # two: out
    sub, mp = effective_block(block, e)
    assert 4 in mp.dropped_images and sub.n_images == 5


# ---------------------------------------------------------------------- the panel
@pytest.fixture
def app(block):
    pytest.importorskip("viser")
    from orientviz.viewer.app import ViewerApp
    from orientviz.viewer.demos import demo_from_block

    block.observations.xy += np.random.default_rng(4).normal(0, 0.004, block.observations.xy.shape)
    a = ViewerApp(demo_from_block(block), host="127.0.0.1", port=0, verbose=False)
    a.panel.adjust(50)
    yield a
    a.stop()


def test_panel_actions_undo_and_rewind(app):
    p = app.panel
    st, act, h = p.state, p.act, p.act.handles
    assert len(st.changes) == 2  # as loaded, adjusted
    h["ray"].value = h["ray"].options[2]
    j = act.chosen_ray()
    res_before = np.asarray(app.scene.nodes["residuals"].points).copy()
    h["toggle_ray"].value = None  # a click, from Python
    assert app.messages == []
    assert not st.edits.obs_on[j] and len(st.changes) == 3
    assert st.result.normalized_residuals is not None  # the precision pass ran
    assert "(off)" in h["ray"].options[2]
    assert not np.array_equal(np.asarray(app.scene.nodes["residuals"].points), res_before)
    assert h["changes"].value.startswith("2. observation")
    assert act.last_timing["answer"] <= act.last_timing["with precision"]
    p.handles["image"].value = 1
    h["toggle_image"].value = None
    assert not st.edits.image_on[1]
    assert tuple(app.scene.image_nodes[1].color) == (175, 175, 175)  # drawn grey
    assert "switched off: 1 ray, 1 image, 0 control points" in h["act_info"].content  # not "1 images"
    assert tuple(app.scene.image_nodes[0].color) == (40, 70, 160)
    h["weight"].value = 0.25
    p.handles["image"].value = 3
    h["set_weight"].value = None
    assert st.edits.weight[act.chosen_ray()] == 0.25 and len(st.changes) == 5
    h["undo"].value = None
    assert st.change_cursor == 3 and np.all(st.edits.weight == 1)
    h["changes"].value = h["changes"].options[1]  # rewind to the adjusted state
    same_state(st, st.changes[1])
    assert "σ̂0" in h["changes"].value


def test_panel_drag_control_point(app):
    p = app.panel
    st, act, h = p.state, p.act, p.act.handles
    h["drag"].value = True
    k = act.chosen_control()
    assert act.drag is not None
    pos = np.asarray(act.drag.position, dtype=float) + app.scene.geo.frame.origin
    np.testing.assert_allclose(pos, st.edits.known[k], atol=1e-3)
    act.drag.position = tuple(np.asarray(act.drag.position) + [0.0, 0.0, 0.3])
    act.drop()  # what the end of a drag in the browser calls
    assert app.messages == []
    assert st.edits.known[k, 2] == pytest.approx(st.changes[1].edits.known[k, 2] + 0.3, abs=1e-3)
    assert "moved" in st.changes[-1].label
    h["undo"].value = None  # the control point and its gizmo go back
    back = np.asarray(act.drag.position, dtype=float) + app.scene.geo.frame.origin
    np.testing.assert_allclose(back, pos, atol=1e-3)
    np.testing.assert_array_equal(st.edits.known[k], st.changes[1].edits.known[k])
    h["auto_precision"].value = False  # large blocks: the quick answer only
    o = st.block.observations
    rays = np.bincount(o.point, minlength=st.block.n_points)
    k = next(k for k, j in enumerate(act.rays) if rays[o.point[j]] >= 3)  # a well-seen point
    h["ray"].value = h["ray"].options[k]
    h["toggle_ray"].value = None
    assert app.messages == []
    assert st.result.normalized_residuals is None and "with precision" not in act.last_timing
    h["auto_precision"].value = True  # switched on again: added to the current state
    assert st.result.normalized_residuals is not None
    assert st.changes[-1].result is st.result


def test_quality_colouring_and_worst_lists(app):
    p = app.panel
    q, h = p.quality, p.quality.handles
    h["measure"].value = "largest normalised residual |w|"
    assert q.quality is not None and q.quality.key == "max_w"
    cols = np.array([np.asarray(n.color) for n in app.scene.image_nodes])
    np.testing.assert_array_equal(cols, q.quality.colours(q.quality.image))
    assert len(h["worst_images"].options) == 1 + 6
    worst = q.worst_images[0]
    assert q.quality.image[worst] == np.nanmax(q.quality.image)
    h["worst_images"].value = h["worst_images"].options[1]
    assert p.handles["image"].value == worst and p.scene.selected == worst
    h["worst_points"].value = h["worst_points"].options[1]
    assert p.scene.selected_point == q.worst_points[0]
    target = p.fly_target + app.scene.geo.frame.origin
    np.testing.assert_allclose(target, p.state.block.points.xyz[q.worst_points[0]])
    h["measure"].value = "role (no quality)"
    assert tuple(app.scene.image_nodes[0].color) == (40, 70, 160)


def test_a_change_the_precision_refuses_is_undone(app, monkeypatch):
    p = app.panel
    st, act, h = p.state, p.act, p.act.handles
    n = len(st.changes)
    before = st.changes[-1]

    def refuse():
        raise ov.NotDeterminableError("1 parameter combination is not determinable")

    monkeypatch.setattr(act, "add_precision", refuse)
    h["toggle_ray"].value = None
    assert app.messages and "not determinable" in app.messages[-1]
    assert len(st.changes) == n and st.edits.obs_on.all()
    same_state(st, before)


def test_a_camera_left_without_images_leaves_the_sub_block(block):
    """Per-camera lens models: a camera whose images are all off is no group of the
    adjustment (it would not be determinable: "parameter group has no image")."""
    b = block.copy()
    b.cameras = replace(
        b.cameras, ids=["a", "b"], c=np.repeat(b.cameras.c, 2), x0=np.repeat(b.cameras.x0, 2),
        y0=np.repeat(b.cameras.y0, 2), format_mm=np.repeat(b.cameras.format_mm, 2, axis=0),
        model=[{"model": "backward", "free": ["c"], "sigma": {}, "values": {}, "r0": None}] * 2,
    )  # fmt: skip
    b.images.camera = np.array([0, 0, 0, 1, 1, 1])
    e = Edits.of(b)
    sub, mp = effective_block(b, e)
    assert mp.cameras is None and len(sub.cameras.ids) == 2
    e.image_on[:3] = False  # every image of camera "a"
    sub, mp = effective_block(b, e)
    assert list(mp.cameras) == [1] and sub.cameras.ids == ["b"]
    assert np.all(sub.images.camera == 0) and len(sub.cameras.model) == 1
    np.testing.assert_array_equal(sub.cameras.c, b.cameras.c[[1]])
