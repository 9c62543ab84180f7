"""Deformation view: morphing between displacement fields, and its nodes in the block demo."""

import numpy as np
import pytest

from orientviz.viewer.deformation import MODES, auto_scale, morph, rms


def test_morph_end_points_and_scale():
    rng = np.random.default_rng(4)
    ref, A, B = rng.normal(size=(3, 10, 3))
    np.testing.assert_allclose(morph(ref, A, B, 0.0, 5.0), ref + 5.0 * A)
    np.testing.assert_allclose(morph(ref, A, B, 1.0, 5.0), ref + 5.0 * B)
    np.testing.assert_allclose(morph(ref, A, B, 0.5, 2.0), ref + A + B)


def test_auto_scale_uses_the_larger_median():
    small = np.full((5, 3), [0.0, 0.0, 0.01])
    large = np.full((5, 3), [0.0, 0.0, 0.04])
    assert auto_scale(small, large, spacing=100.0) == pytest.approx(0.5 * 100.0 / 0.04)
    assert auto_scale(np.zeros((3, 3)), spacing=10.0) == 1.0
    np.testing.assert_allclose(rms(large), [0.0, 0.0, 0.04])


def test_block_demo_deformation_nodes():
    pytest.importorskip("viser")
    from orientviz.viewer.app import ViewerApp
    from orientviz.viewer.demos import load_demo

    app = ViewerApp(load_demo("block"), port=0, verbose=False)
    try:
        ctl = app.extra["deformation"]
        vec, pts = app.extra["deformation_nodes"]
        origin = app.scene.geo.frame.origin
        demo = app.demo
        ctl["show"].value = True
        assert vec.visible and not app.scene.nodes["residuals"].visible
        ctl["t"].value = 0.0  # reference → estimate at t = 0: the reference itself
        ref = app.extra["deformation_reference"]
        # float32 scene coordinates of a few km: a few 0.1 mm
        np.testing.assert_allclose(np.asarray(pts.points, dtype=float) + origin, ref, atol=2e-3)
        app.panel.adjust(50)  # the listeners redraw with the adjusted points
        ctl["t"].value = 1.0
        moved = np.asarray(pts.points, dtype=float) + origin
        d = demo.state.block.points.xyz - ref
        k = auto_scale(d, spacing=app.scene.geo.spacing)
        np.testing.assert_allclose(moved, ref + k * d, atol=2e-3)
        ctl["mode"].value = MODES[1]  # two bundles: without and with Ebner's 12 parameters
        assert "with ebner12" in ctl["info"].content
        assert app.messages == []
    finally:
        app.stop()
