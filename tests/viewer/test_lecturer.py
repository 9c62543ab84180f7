"""What a lecturer sees (issue 31, points 4, 7, 8, 10), through the viewer's state."""

import numpy as np
import pytest

from orientviz.viewer.app import ViewerApp
from orientviz.viewer.block_geometry import COLORS
from orientviz.viewer.shapes import ramp

pytest.importorskip("viser")


@pytest.fixture(scope="module")
def camcal():
    app = ViewerApp("dbat_camcal", port=0, verbose=False)
    yield app
    app.stop()


def test_camera_terms_with_sigma_and_correlations(camcal):
    cam = camcal.panel.camera
    assert cam.handles["folder"].visible
    text = cam.handles["table"].content
    for name in ("c =", "x0 =", "K1 =", "P2 =", "strongest correlations"):
        assert name in text
    k1, s1 = camcal.demo.state.result.camera.get("K1")
    assert f"K1 = {k1:.6g} ± {s1:.2g}" in text
    # the distortion field of the estimated lens is drawn on the selected image
    assert cam.node is not None and cam.field_max_um > 10
    cam.handles["field"].value = False
    cam.refresh()
    assert cam.node is None
    cam.handles["field"].value = True
    cam.refresh()


def test_no_camera_folder_without_camera_terms():
    app = ViewerApp("block_strip", port=0, verbose=False)
    try:
        assert not app.panel.camera.handles["folder"].visible
    finally:
        app.stop()


def test_legend_names_what_is_drawn_and_only_that(camcal):
    p = camcal.panel
    p.update_legend()
    text = p.handles["legend"].content
    assert "tie" in text and "control" in text
    assert "check" not in text  # camcal has no check points
    assert "strips" not in text  # nor strips
    assert "residuals ×" in text and "lens distortion" in text
    p._show("points", False)
    assert " tie" not in p.handles["legend"].content
    p._show("points", True)
    assert " tie" in p.handles["legend"].content


def test_selection_colour_is_outside_the_quality_scale():
    from orientviz.viewer.quality import STOPS

    stops = np.vstack(  # the residuals' ramp and the quality colours' ramp
        [ramp(np.linspace(0.0, 1.0, 41), 1.0), ramp(np.linspace(0.0, 1.0, 41), 1.0, STOPS)]
    ).astype(float)
    for key in ("selected", "ray_selected"):
        d = np.linalg.norm(stops - np.asarray(COLORS[key], float), axis=1)
        assert d.min() > 120, key


def test_flown_to_observation_is_marked(camcal):
    p, st = camcal.panel, camcal.demo.state
    j = int(st.largest(1)[0])
    p.fly_to_observation(j)
    assert p.scene.selected_point == int(st.block.observations.point[j])
    assert "selected_point" in p.scene.nodes


def test_scrubbing_back_hides_the_adjustments_ellipsoids():
    app = ViewerApp("block_compact", port=0, verbose=False)
    try:
        p = app.panel
        assert "ellipsoids" in p.scene.nodes
        p.replay(0)
        assert "ellipsoids" not in p.scene.nodes and "station_ellipsoids" not in p.scene.nodes
        p.replay(len(app.demo.state.history) - 1)
        assert "ellipsoids" in p.scene.nodes
    finally:
        app.stop()


def test_residual_scale_stays_while_iterating_and_replaying():
    app = ViewerApp("block", port=0, verbose=False)
    try:
        p, scene = app.panel, app.scene
        k0, bar = scene.exaggeration, scene.scale_bar_text
        p.adjust(1)
        p.adjust(50)
        p.replay(0)
        p.replay(len(app.demo.state.history) - 1)
        assert scene.exaggeration == k0 and scene.scale_bar_text == bar
        p.set_exaggeration(auto=True)  # on request only
        assert scene.exaggeration > 10 * k0 and scene.scale_bar_text != bar
    finally:
        app.stop()


def test_pair_arrows_keep_their_scale_while_orienting():
    app = ViewerApp("pair", port=0, verbose=False)
    try:
        pv = app.extra["pair"]
        k0 = pv.k
        pv._passes(30)
        assert pv.k == k0
        pv.rescale()
        assert pv.k > 10 * k0
    finally:
        app.stop()


def test_export_carries_the_panels_numbers_and_legend(tmp_path):
    """`view FILE --export` writes the adjusted state with σ̂0 and the legend in a box."""
    from orientviz.io.solve import load_named, solve_problem
    from orientviz.viewer.app import export_html

    out = export_html("block_compact", tmp_path / "b.html")
    page = out.read_text()
    sigma0 = f"{solve_problem(load_named('block_compact')).adjustment.sigma0:.10g}"
    box = page[page.index('<div id="orientviz-panel"') :]
    assert sigma0 in box and "residual vectors" in box and "<b>" in box
    assert "__VISER_EMBED_DATA__" in page


def test_legend_runs_keep_the_colours():
    from orientviz.viewer.legend import swatch
    from orientviz.viewer.snapshot import runs

    md = f"**σ0** 1.5  \n{swatch((1, 2, 3), '●')} tie points"
    assert runs(md) == [[(None, "σ0 1.5")], [((1, 2, 3), "●"), (None, " tie points")]]
