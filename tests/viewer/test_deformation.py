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


def test_self_calibration_comparison_shows_its_gain():
    """Issue 31: the demo's comparison showed no gain (tie-point RMS 0.201 → 0.207 m): its
    random errors hide the deformation. On the systematic errors alone (the same images
    without random errors and blunders) Ebner's 12 parameters remove most of it."""
    from orientviz.simulate import simulate_block
    from orientviz.simulate.systematic import typical
    from orientviz.viewer.deformation import self_calibration_comparison
    from orientviz.viewer.demos import SEED, _systematic_twin

    sim = simulate_block(
        3, 8, rng=SEED, gross={"count": 4, "size_mm": 0.04}, systematic=typical(10.0)
    )
    twin = _systematic_twin(sim, SEED, 3, 8)
    assert twin is not None
    np.testing.assert_array_equal(twin.observations.point, sim.block.observations.point)
    A, B, text = self_calibration_comparison(sim.block, sim.truth, twin)
    tie = twin.points.role == 0
    without, with_ = np.linalg.norm(rms(A[tie])), np.linalg.norm(rms(B[tie]))
    assert with_ < 0.5 * without  # the deformation is mostly removed
    assert "systematic image errors alone" in text and "% removed" in text
    assert "the gain does not show there" in text


def test_lens_model_deformation_of_a_problem_file():
    """Issue 31 pt 4: dbat_camcal adjusted without its lens terms against with them."""
    pytest.importorskip("viser")
    from orientviz.viewer.app import ViewerApp

    app = ViewerApp("dbat_camcal", port=0, verbose=False)
    try:
        ctl, vec = app.extra["lens_deformation"], app.extra["lens_deformation_node"]
        field = app.extra["lens_field"]
        st = app.panel.state
        ctl["show"].value = True
        assert vec.visible and not app.scene.nodes["residuals"].visible
        A = field["A"]
        assert A.shape == (st.block.n_points, 3) and np.all(np.isfinite(A))
        # without the lens terms the model does not fit: σ̂0 far above the solution's
        assert field["sigma0"] > 5 * st.result.sigma0
        assert np.linalg.norm(rms(A)) > 0
        seg = np.asarray(vec.points, float) + app.scene.geo.frame.origin
        np.testing.assert_allclose(seg[:, 0], st.block.points.xyz, atol=1e-4)  # from the solution
        assert "without" in ctl["info"].content and app.messages == []
        legend = app.panel.handles["legend"].content
        assert "model deformation" in legend and "residual vectors" not in legend
        ctl["show"].value = False
        legend = app.panel.handles["legend"].content
        assert "model deformation" not in legend and "residual vectors" in legend
        assert not vec.visible and app.scene.nodes["residuals"].visible
    finally:
        app.stop()
