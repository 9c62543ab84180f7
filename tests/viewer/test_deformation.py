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
        legend = app.panel.handles["legend"]
        assert "model deformation" not in legend.content and "residual vectors" in legend.content
        ctl["show"].value = True
        assert vec.visible and not app.scene.nodes["residuals"].visible
        # the legend names the deformation's arrows and points, not what it hid
        assert "model deformation: each point from its true position" in legend.content
        assert "residual vectors" not in legend.content and "tie" not in legend.content
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
        assert "adjusted without (t = 0) and with (t = 1) self-calibration" in legend.content
        ctl["show"].value = False
        assert "model deformation" not in legend.content and "residual vectors" in legend.content
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


def write_ap_file(folder, name: str):
    """A problem file whose camera has the additional-parameter set ``name`` (``cameras[]
    .additional``), on a simulated block with a barrel distortion (15 µm at r = 80 mm)."""
    import json

    from orientviz.io.problem import dumps_problem, problem_from_block
    from orientviz.simulate import simulate_block

    def barrel(xy, image):
        return -3e-8 * (xy**2).sum(axis=1, keepdims=True) * xy  # mm

    sim = simulate_block(3, 6, rng=5, control="full", systematic=barrel)
    doc = json.loads(dumps_problem(problem_from_block(sim.block, columnar=False)))
    doc["cameras"][0].update(additional=name)
    path = folder / f"{name}.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def ap_file(tmp_path_factory):
    """:func:`write_ap_file` with Ebner's 12 parameters."""
    return write_ap_file(tmp_path_factory.mktemp("ap"), "ebner12")


@pytest.mark.parametrize("name", ["brown", "gruen44"])
def test_brown_and_gruen44_sets_reach_the_view_as_solve_estimates_them(name, tmp_path):
    """The set named in the file (not another, not none) is what the viewer solves with,
    lists and draws: σ̂0, the parameter names and values of ``solve``, and the correction
    field of that set's own model at the estimates."""
    pytest.importorskip("viser")
    from orientviz.bundle import ap_set, block_camera_options
    from orientviz.io.solve import load_named, solve_problem
    from orientviz.viewer.app import ViewerApp
    from orientviz.viewer.panel_camera import ap_distortion_vectors

    path = write_ap_file(tmp_path, name)
    problem = load_named(str(path))
    ref = solve_problem(problem).adjustment
    sl = ref.groups["additional"]
    aps = block_camera_options(problem.data)["additional"]  # the set as solve builds it
    assert aps.name == name and list(aps.names) == list(ap_set(name).names)
    app = ViewerApp(str(path), port=0, verbose=False)
    try:
        st, cam = app.panel.state, app.panel.camera
        assert st.result.sigma0 == pytest.approx(ref.sigma0, rel=1e-9)
        lines = cam.text.split("\n")
        assert len(lines) == len(aps.names) + 1
        for label, value, line in zip(ref.names[sl], ref.x[sl], lines, strict=False):
            assert line.startswith(f"{label} = {value:.4g} ± ")
        assert [str(n).split("@")[0] for n in ref.names[sl]] == list(aps.names)
        # the field drawn on the selected image is the set's correction at the estimates
        b = st.block
        xy = b.observations.xy
        m, d = ap_distortion_vectors(aps, ref.x[sl], xy.min(axis=0), xy.max(axis=0))
        assert cam.field_max_um == pytest.approx(1e3 * np.linalg.norm(d, axis=1).max(), rel=1e-9)
        assert f"additional parameters ({name})" in app.panel.handles["legend"].content
        assert app.messages == []
    finally:
        app.stop()


def test_additional_parameter_set_of_a_file_in_the_panel_and_its_deformation(ap_file):
    """Issue 31 pt 4: an additional-parameter set given in a problem file — its estimates
    with σ and strongest correlations, its correction field and the model deformation
    (the block adjusted without the set against with it)."""
    pytest.importorskip("viser")
    from orientviz.io.solve import load_named, solve_problem
    from orientviz.viewer.app import ViewerApp
    from orientviz.viewer.panel_camera import DISTORTION_COLOUR

    ref = solve_problem(load_named(str(ap_file))).adjustment
    app = ViewerApp(str(ap_file), port=0, verbose=False)
    try:
        st, cam = app.panel.state, app.panel.camera
        assert st.result.sigma0 == pytest.approx(ref.sigma0, rel=1e-9)
        # the camera folder: 12 parameters, each value ± σ in µm, the σ the solve's
        sl = ref.groups["additional"]
        sig = ref.sigma0 * np.sqrt(np.diag(ref.cofactor_groups["additional"]))
        lines = cam.text.split("\n")
        assert cam.handles["folder"].visible and len(lines) == 13
        for name, s, line in zip(ref.names[sl], sig, lines, strict=False):
            assert line.startswith(f"{name} = ") and f"± {s:.2g} µm" in line
        assert lines[-1].startswith("strongest correlations: ")
        # the correction field of the estimated set on the selected image
        assert cam.node is not None and "additional parameters (ebner12)" in (
            app.panel.handles["legend"].content
        )
        assert np.asarray(cam.node.colors).reshape(-1, 3)[0].tolist() == list(DISTORTION_COLOUR)
        # the model deformation: once more without the set
        ctl, field = app.extra["lens_deformation"], app.extra["lens_field"]
        ctl["show"].value = True
        assert "**without** the additional parameters (ebner12) (t = 0)" in ctl["info"].content
        pinhole = load_named(str(ap_file))
        pinhole.data.cameras.model = [{}]
        plain = solve_problem(pinhole).adjustment
        assert field["sigma0"] == pytest.approx(plain.sigma0, rel=1e-9)
        assert field["sigma0"] > 1.2 * st.result.sigma0  # the barrel shows without the set
        p = st.block.n_points
        A = plain.x[plain.groups["points"]].reshape(p, 3) - st.block.points.xyz
        np.testing.assert_allclose(field["A"], A, atol=1e-9)
        assert app.messages == []
    finally:
        app.stop()


def test_misclosure_at_the_estimate_is_the_adjustments_own(ap_file):
    """Opening a self-calibrated block builds no second bundle problem: at the estimate the
    misclosure is −v of the adjustment, equal to the one through the camera model."""
    pytest.importorskip("viser")
    from orientviz.viewer import solved

    for target in (str(ap_file), "dbat_camcal"):
        st = solved.solution_demo(solved.solve_target(target)).state
        assert st.at_result and st.camera is not None
        fast = st.misclosure()
        assert st.camera._cache is None  # no bundle problem built for it
        full = st.camera.misclosure(st.block, st.ap)
        np.testing.assert_allclose(fast, full, rtol=0, atol=1e-12 * np.abs(full).max())
        st.replay(0)  # another state: through the camera model
        assert not st.at_result
        np.testing.assert_array_equal(st.misclosure(), st.camera.misclosure(st.block, st.ap))
