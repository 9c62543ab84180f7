"""The design studio without a browser: measures, plan changes, clicks, undo."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from orientviz.design import FlightDesign
from orientviz.viewer.app import ViewerApp
from orientviz.viewer.studio import MEASURES, Studio, point_values, scale_of
from orientviz.viewer.studio_panel import CLICKS, StudioView, ellipsoid_mesh


@pytest.fixture(scope="module")
def view():
    app = ViewerApp(None, port=0, verbose=False)
    studio = Studio(
        FlightDesign(strips=2, images_per_strip=6, control="perimeter", control_spacing=2)
    )
    sv = StudioView(app, studio)
    sv.build()
    yield sv
    app.stop()


def test_every_measure_colours_the_points(view):
    st = view.studio
    for key in MEASURES:
        v = point_values(st.quality, st.block, key)
        assert v.shape == (st.block.n_points,) and np.isfinite(v).any()
        st.measure = key
        view.redraw()
        s = scale_of(v, key)
        assert s.lo <= np.nanmin(v[np.isfinite(v)]) and view.colours.shape == (v.size, 3)
        assert MEASURES[key][0] in view.panel.h["legend"].content
    st.measure = "sigma_z"
    view.redraw()


def test_a_click_on_the_ground_makes_the_nearest_point_control_and_undo(view):
    st, panel = view.studio, view.panel
    tie = np.flatnonzero(st.block.points.role == 0)
    j = int(tie[len(tie) // 2])
    target = view.frame.to_scene(st.block.points.xyz[j])
    origin = target + np.array([30.0, -20.0, 1500.0])
    event = SimpleNamespace(
        ray_origin=tuple(origin),
        ray_direction=tuple((target - origin) / np.linalg.norm(target - origin)),
    )
    before = st.quality.point_sigma[j, 2]
    panel.h["click"].value = CLICKS["control"]
    panel._clicked(event)
    assert st.block.points.role[j] == 1 and st.quality.point_sigma[j, 2] < before
    assert st.block.points.ids[j] in panel.h["changes"].content
    panel.undo()
    assert st.block.points.role[j] == 0
    panel.h["click"].value = CLICKS["nothing"]


def test_apply_plan_builds_the_new_design(view):
    panel, st = view.panel, view.studio
    panel.h["strips"].value = 3
    panel.h["gnss"].value = 0.1
    panel.h["apr"].value = 0.3
    panel.h["gnss_offsets"].value = True
    panel.apply_plan()
    assert st.design.strips == 3 and st.design.sigma_gnss == pytest.approx(0.1)
    assert st.design.sigma_apr == pytest.approx(0.3) and st.design.sigma_statoscope is None
    assert [a.kind for a in st.live.auxiliary] == ["gnss", "apr"]
    assert "(shift per strip)" in panel.h["summary"].content
    assert "APR σ 0.30 m" in panel.h["summary"].content
    assert st.block.n_images == 18
    assert "3 strips × 6 images" in panel.h["summary"].content
    assert "plan: 3 × 6" in panel.h["changes"].content
    panel.undo()  # the plan before
    assert st.design.strips == 2 and st.block.n_images == 12 and not st.live.auxiliary
    panel.h["apr"].value = 0.0
    panel.h["gnss_offsets"].value = False


def test_cross_strip_and_removals_by_click_and_their_undo(view):
    panel, st = view.panel, view.studio
    n0, z0 = st.block.n_images, st.quality.summary["sigma_z_rms"]
    x_end = float(st.block.images.X0[:, 0].max())
    panel.act_at((x_end, 0.0), "cross")
    assert st.block.n_images > n0 and st.block.images.strip.max() == 2
    # new images with their own unknowns can only make the others' σ smaller
    assert st.quality.summary["sigma_z_rms"] < z0
    assert "cross strip at X" in panel.h["changes"].content
    panel.undo()
    assert st.block.n_images == n0
    assert st.quality.summary["sigma_z_rms"] == pytest.approx(z0, rel=1e-12)
    X0 = st.block.images.X0
    between = 0.5 * (X0[2, :2] + X0[3, :2])
    z_between = st.quality.point_sigma[:, 2].copy()
    panel.act_at(between, "add")
    assert st.block.n_images == n0 + 1
    np.testing.assert_allclose(st.block.images.X0[-1], [*between, X0[2, 2]])
    assert st.block.images.strip[-1] == st.block.images.strip[2]
    assert np.all(st.quality.point_sigma[:, 2] <= z_between * (1 + 1e-9))
    assert "added at X" in panel.h["changes"].content
    panel.undo()
    panel.act_at(X0[3, :2] + 10.0, "image")
    assert st.block.n_images == n0 - 1 and st.block.images.ids[3] != "000_003"
    panel.undo()
    panel.act_at(X0[0, :2], "strip")
    assert st.block.n_images == n0 // 2
    panel.undo()
    assert st.block.n_images == n0


def test_method_switch_and_the_polynomial_says_it_has_no_precision(view):
    panel, st = view.panel, view.studio
    zb = st.quality.point_sigma[:, 2].copy()
    panel.h["method"].value = "independent models (7 parameters per model)"
    panel.set_method()
    zm = st.quality.point_sigma[:, 2]
    assert st.method == "models" and not np.allclose(zm, zb, rtol=1e-3, equal_nan=True)
    assert "not defined for independent models" in panel.h["summary"].content
    st.measure = "redundancy"
    view.redraw()  # no redundancy for models: grey, no error
    st.measure = "sigma_z"
    panel.h["method"].value = "polynomial strip adjustment"
    panel.set_method()
    assert "no design precision" in panel.h["summary"].content
    assert np.allclose(st.quality.point_sigma[:, 2], zb, equal_nan=True)
    panel.h["method"].value = "bundle adjustment"
    panel.set_method()


def test_control_changes_with_the_models_method_are_updates_of_one_factorisation():
    from orientviz.design import LiveModels, assess_models
    from orientviz.errors import NotDeterminableError

    st = Studio(FlightDesign(strips=3, images_per_strip=8, control_spacing=4))
    st.set_method("models")
    live = st._models
    assert isinstance(live, LiveModels)
    tie = np.flatnonzero(st.block.points.role == 0)
    for j in tie[[3, len(tie) // 2]]:
        st.set_control(int(j), 0.02)
    st.set_control(int(tie[3]), None)
    st.undo()
    assert st._models is live and len(live._steps) == 4  # updates, no new factorisation
    ref = assess_models(st.block, st.spec)  # rtol: tests/design/test_models_live.py
    np.testing.assert_allclose(st.quality.point_sigma, ref.point_sigma, rtol=1e-8)
    n0, log0 = st.block.n_images, list(st.log)
    with pytest.raises(NotDeterminableError, match="common points"):
        st.remove_images([9])  # inside a strip: its neighbours form no model
    assert st.block.n_images == n0 and st.log == log0 and st._models is live
    st.remove_images([0])  # a new structure: a new factorisation
    assert st._models is not live
    ref = assess_models(st.block, st.spec)
    np.testing.assert_allclose(st.quality.point_sigma, ref.point_sigma, rtol=1e-8)
    st.undo()
    assert st._models is live


def test_ellipsoids_and_the_gizmo(view):
    panel, st = view.panel, view.studio
    panel.h["ellipsoids"].value = True
    view.redraw()
    assert "ellipsoids" in view.nodes
    panel.h["ellipsoids"].value = False
    view.redraw()
    assert "ellipsoids" not in view.nodes
    view.gizmo(True)
    tie = np.flatnonzero(st.block.points.role == 0)
    j = int(tie[0])
    view.gizmo_released(view.frame.to_scene(st.block.points.xyz[j]) + 5.0)
    assert st.block.points.role[j] == 1
    panel.undo()
    view.gizmo(False)
    assert "gizmo" not in view.nodes


def test_ellipsoid_mesh_has_the_semi_axes():
    dirs = np.eye(3)[None]
    V, F = ellipsoid_mesh(np.zeros((1, 3)), np.array([[1.0, 2.0, 5.0]]), dirs)
    assert F.shape[1] == 3 and V.shape[0] == 42
    assert np.abs(V).max(axis=0) == pytest.approx([1.0, 2.0, 5.0], rel=0.1)


def test_a_method_that_cannot_take_the_design_keeps_the_old_one():
    from orientviz.errors import NotDeterminableError

    st = Studio(FlightDesign(strips=3, images_per_strip=9, control="corners"))
    st.add_cross_strip(float(st.block.images.X0[:, 0].mean()))
    assert "plan without the images added" in st.law["note"]
    with pytest.raises(NotDeterminableError, match="fewer than 5 common points"):
        st.set_method("models")  # the cross strip's end models cannot be formed
    assert st.method == "bundle" and np.isfinite(st.quality.point_sigma).all()


def test_moving_an_image_updates_the_design_like_a_new_assessment(view):
    from orientviz.design import assess_block

    st = view.studio
    n0, ids0 = st.block.n_images, list(st.block.images.ids)
    X0 = st.block.images.X0
    to = X0[3, :2] + [150.0, -80.0]
    st.move_image(3, to)
    b = st.block
    assert b.n_images == n0 and sorted(b.images.ids) == sorted(ids0)
    k = b.images.ids.index(ids0[3])
    np.testing.assert_allclose(b.images.X0[k], [*to, X0[3, 2]])
    ref = assess_block(b, st.spec)[1]  # the two update steps equal a new assessment
    np.testing.assert_allclose(st.quality.point_sigma, ref.point_sigma, rtol=1e-7)
    np.testing.assert_allclose(st.quality.redundancy, ref.redundancy, atol=1e-9)
    assert "moved to X" in st.changes_markdown()
    st.undo()
    assert list(st.block.images.ids) == ids0


def test_the_image_gizmo_drags_an_image(view):
    panel, st = view.panel, view.studio
    X0 = st.block.images.X0.copy()
    panel.act_at(X0[4, :2] + 5.0, "pick")  # the gizmo on the nearest image
    assert "image_gizmo" in view.nodes and view.dragged == st.block.images.ids[4]
    to = X0[4] + [120.0, 60.0, 0.0]
    view.image_released(view.frame.to_scene(to))
    k = st.block.images.ids.index(view.dragged)
    np.testing.assert_allclose(st.block.images.X0[k], to)
    assert "moved to X" in panel.h["changes"].content
    panel.undo()
    np.testing.assert_allclose(st.block.images.X0, X0)
    view.image_gizmo(False)
    assert "image_gizmo" not in view.nodes


def test_structural_changes_with_auxiliary_data_follow_the_readings():
    from orientviz.design import assess_block, design_auxiliary

    st = Studio(FlightDesign(strips=2, images_per_strip=6, control="corners", sigma_statoscope=0.3))
    st.add_cross_strip(float(st.block.images.X0[:, 0].mean()))
    aux = design_auxiliary(st.block, st.design)  # the readings of the new block's images
    assert aux[0].index.size == st.block.n_images
    ref = assess_block(st.block, st.spec, auxiliary=aux)[1]
    np.testing.assert_allclose(st.quality.point_sigma, ref.point_sigma, rtol=1e-7)
    q = st.set_control(int(np.flatnonzero(st.block.points.role == 0)[4]), 0.05)  # an update
    ref = assess_block(st.block, st.spec, auxiliary=aux)[1]
    np.testing.assert_allclose(q.point_sigma, ref.point_sigma, rtol=1e-7)
    st.move_image(2, st.block.images.X0[2, :2] + 100.0)
    ref = assess_block(st.block, st.spec, auxiliary=design_auxiliary(st.block, st.design))[1]
    np.testing.assert_allclose(st.quality.point_sigma, ref.point_sigma, rtol=1e-7)


def test_structural_changes_under_models_update_the_bundle_when_it_is_shown():
    """Under the models method an image removed or moved changes the block at once and the
    models design of it; the bundle's update follows when the bundle is shown again (or a
    control change needs it), equal to a new assessment then."""
    from orientviz.design import assess_block, assess_models
    from orientviz.viewer.studio_live import PendingDesign

    st = Studio(FlightDesign(strips=3, images_per_strip=8, control_spacing=4))
    bundle0 = st.live
    st.set_method("models")
    ends = [int(np.flatnonzero(st.block.images.strip == s)[-1]) for s in range(3)]
    st.remove_images([ends[0]])
    st.move_image(ends[1] - 1, st.block.images.X0[ends[1] - 1, :2] + [60.0, 0.0])
    assert isinstance(st._live, PendingDesign) and st._live.base is bundle0
    ref = assess_models(st.block, st.spec)
    np.testing.assert_allclose(st.quality.point_sigma, ref.point_sigma, rtol=1e-8)
    models = st._models
    tie = np.flatnonzero(st.block.points.role == 0)
    q = st.set_control(int(tie[len(tie) // 2]), 0.02)  # needs the bundle: applied now
    assert not isinstance(st._live, PendingDesign) and st._models is models
    ref = assess_models(st.block, st.spec)
    np.testing.assert_allclose(q.point_sigma, ref.point_sigma, rtol=1e-8)
    st.set_method("bundle")
    ref = assess_block(st.block, st.spec)[1]
    np.testing.assert_allclose(st.quality.point_sigma, ref.point_sigma, rtol=1e-7)
    np.testing.assert_allclose(st.quality.redundancy, ref.redundancy, atol=1e-9)
    st.set_method("models")
    st.remove_images([ends[2] - 1])  # pending again; undone before it is applied
    st.undo()
    assert st._live is not None and not isinstance(st._live, PendingDesign)
    st.undo()  # the control change
    st.undo()  # the move: a pending change, applied by the control change
    st.undo()
    assert st.live is bundle0 and st.block.n_images == 24


def test_a_callback_after_stop_sends_nothing_to_the_stopped_server():
    """A redraw that a click started can arrive after the viewer stopped: it does nothing,
    so viser never warns of a message queued on a closed connection."""
    import warnings

    app = ViewerApp(None, port=0, verbose=False)
    sv = StudioView(app, Studio(FlightDesign(strips=2, images_per_strip=4)))
    sv.build()
    runs = []

    def redraw():
        runs.append(1)
        sv.redraw()

    callback = app.guard(redraw)
    callback()
    assert runs == [1]
    app.stop()
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        callback()
    assert runs == [1] and app.gate.closed
    assert not [w for w in seen if "closed connection" in str(w.message)]
