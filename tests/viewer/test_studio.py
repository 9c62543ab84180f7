"""The design studio without a browser: measures, plan changes, clicks, undo."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from orientviz.design import FlightDesign
from orientviz.viewer.app import ViewerApp
from orientviz.viewer.studio import MEASURES, Studio, point_values, scale_of
from orientviz.viewer.studio_panel import StudioView


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
    panel._clicked(event)
    assert st.block.points.role[j] == 1 and st.quality.point_sigma[j, 2] < before
    assert st.block.points.ids[j] in panel.h["changes"].content
    panel.undo()
    assert st.block.points.role[j] == 0


def test_apply_plan_builds_the_new_design(view):
    panel, st = view.panel, view.studio
    panel.h["strips"].value = 3
    panel.h["gnss"].value = 0.1
    panel.apply_plan()
    assert st.design.strips == 3 and st.design.sigma_gnss == pytest.approx(0.1)
    assert st.block.n_images == 18
    assert "3 strips × 6 images" in panel.h["summary"].content
    assert "plan: 3 × 6" in panel.h["changes"].content
