"""The viewer application without a browser: CLI, errors, export, panel actions."""

import argparse
import contextlib
import socket

import numpy as np
import pytest

import orientviz as ov
from orientviz.viewer.app import ViewerApp, port_is_free, run_from_cli
from orientviz.viewer.demos import demo_from_block

pytest.importorskip("viser")


def args(**kw):
    base = dict(target=None, host="127.0.0.1", port=0, export=None)
    base.update(kw)
    return argparse.Namespace(**base)


@pytest.fixture
def app(block):
    rng = np.random.default_rng(8)
    block.observations.xy += rng.normal(0, 0.005, block.observations.xy.shape)  # 5 µm noise
    block.images.X0 += rng.normal(0, 3.0, block.images.X0.shape)  # start errors, 3 m
    demo = demo_from_block(block)
    a = ViewerApp(demo, port=0, verbose=False)
    yield a
    a.stop()


def test_port_in_use_is_one_line_and_exit_2(capsys):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen(1)
        port = s.getsockname()[1]
        assert not port_is_free("127.0.0.1", port)
        code = run_from_cli(args(target="block", port=port))
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert (
        err
        == f"orientviz view: port {port} on 127.0.0.1 is already in use; choose another with --port"
    )


def test_a_port_left_in_time_wait_is_free_again():
    """A viewer stopped a moment ago leaves its browser's connections in TIME_WAIT (about a
    minute): `orientviz view` run again on the same port must not be refused for that."""
    with socket.socket() as listener:
        listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as viser's server
        listener.bind(("127.0.0.1", 0))
        listener.listen(1)
        port = listener.getsockname()[1]
        client = socket.create_connection(("127.0.0.1", port))
        conn, _ = listener.accept()
        conn.close()  # the server closes first: its end of the connection enters TIME_WAIT
        client.close()
    with socket.socket() as plain:  # the state the probe must see through
        with pytest.raises(OSError):
            plain.bind(("127.0.0.1", port))
    assert port_is_free("127.0.0.1", port)


def test_bad_file_is_reported_in_viewer_not_raised(tmp_path, capsys):
    bad = tmp_path / "broken.json"
    bad.write_text("{ not json")
    a = ViewerApp(str(bad), port=0, verbose=False)
    try:
        assert a.messages, "the load error must be shown"
        assert "broken.json" in a.messages[0]
        assert a._message_md.visible and "broken.json" in a._message_md.content
        assert "broken.json" in capsys.readouterr().err
    finally:
        a.stop()


def test_unknown_target_export_exits_2(tmp_path, capsys):
    code = run_from_cli(
        args(target=str(tmp_path / "missing.json"), export=str(tmp_path / "x.html"))
    )
    assert code == 2
    assert "missing.json" in capsys.readouterr().err
    assert not (tmp_path / "x.html").exists()


def test_export_html_is_self_contained(tmp_path, block):
    out = tmp_path / "block.html"
    a = ViewerApp(demo_from_block(block), port=0, verbose=False)
    try:
        a.export_html(out)
    finally:
        a.stop()
    html = out.read_text()
    assert "__VISER_EMBED_DATA__" in html  # the scene is embedded
    assert "ws://" not in html.split("__VISER_EMBED_DATA__")[1][:100]
    assert "<script" in html and 'src="http' not in html  # no external scripts


def test_slider_moves_image_and_redraws(app):
    p = app.panel
    st = app.demo.state
    before = np.asarray(app.scene.nodes["residuals"].points).copy()
    a0 = st.block.images.angles[0].copy()
    p.handles["phi"].value = 0.25  # gon
    np.testing.assert_allclose(
        st.block.images.angles[0], a0 + [0, ov.to_rad(0.25, "gon"), 0], atol=1e-15
    )
    after = np.asarray(app.scene.nodes["residuals"].points)
    assert np.any(np.abs(after - before) > 0)
    assert p.last_redraw_s < 1.0


def test_adjust_scrub_reset(app):
    p, st = app.panel, app.demo.state
    p.handles["step"].value = None  # a click on "one iteration", from Python
    assert len(st.history) == 2 and st.cursor == 1
    p.adjust(50)
    n = len(st.history)
    assert n > 2 and st.result.converged
    assert p.handles["iteration"].max == n - 1
    p.handles["iteration"].value = 0  # scrub back to the start values
    np.testing.assert_allclose(st.block.images.X0, st.block0.images.X0)
    p.handles["iteration"].value = n - 1
    np.testing.assert_allclose(st.block.images.X0, st.history[-1].X0)
    assert st.at_result
    p.reset()
    assert len(st.history) == 1


def test_failing_adjustment_is_reported(block):
    def broken(b, max_iter):
        raise np.linalg.LinAlgError("singular matrix")

    demo = demo_from_block(block)
    demo.state.adjuster = broken
    a = ViewerApp(demo, port=0, verbose=False)
    try:
        a.panel.guard(lambda: a.panel.adjust(1))()
        assert a.messages and "singular matrix" in a.messages[-1]
    finally:
        a.stop()


def test_largest_residual_list_and_fly_to(app):
    st = app.demo.state
    st.block.observations.xy[7] += [0.2, 0.0]  # a blunder of 200 µm in observation 7
    app.panel.refresh()
    labels = app.panel.handles["largest"].options
    scores, kind = st.scores()
    assert kind == "|v|/σ"
    order = np.argsort(-scores)[: len(labels)]
    assert [lab.split()[1] for lab in labels] == [st.observation_label(j) for j in order]
    app.panel.fly_to_observation(7)
    assert app.panel.handles["image"].value == int(st.block.observations.image[7])
    target = app.panel.fly_target + app.scene.geo.frame.origin
    np.testing.assert_allclose(target, st.block.points.xyz[st.block.observations.point[7]])


def test_shipped_block_file_loads_and_adjusts():
    from pathlib import Path

    import orientviz

    path = Path(orientviz.__file__).parent / "datasets" / "examples" / "block_strip.json"
    if not path.exists():
        pytest.skip("example problem files not shipped in this checkout")
    a = ViewerApp(str(path), port=0, verbose=False)
    try:
        assert a.messages == [] and a.panel is not None
        a.panel.adjust(50)
        assert a.messages == [] and a.demo.state.result.converged
    finally:
        a.stop()


def test_non_block_file_opens_with_its_solution():
    a = ViewerApp("similarity_example", port=0, verbose=False)
    try:
        assert a.messages == [] and a.demo.solution is not None
        assert a.demo.solution.kind == "similarity"
    finally:
        a.stop()


def test_result_without_per_iteration_parameters_still_replays(block):
    from dataclasses import replace

    from orientviz.viewer.state import BlockState

    noisy = block.copy()
    noisy.images.X0 += 2.0
    from orientviz.bundle import bundle_adjust

    res = bundle_adjust(noisy, history_x=True)
    res.history = [replace(it, x=np.zeros(0)) for it in res.history]  # as large bundles do
    st = BlockState(noisy, res)
    assert [s.label for s in st.history] == ["start", "adjusted"]
    np.testing.assert_allclose(st.block.images.X0, res["exterior"].reshape(-1, 6)[:, :3])
    st.replay(0)
    np.testing.assert_allclose(st.block.images.X0, noisy.images.X0)


def test_the_scene_is_lit_without_an_environment_map(monkeypatch):
    """viser's default HDR environment map blocked a software-WebGL page ~15 s before its
    first picture (benchmarks/README.md, "The viewer in the browser"): the viewer turns it
    off and lights the scene by the default lights, without shadows."""
    import viser

    calls = []
    monkeypatch.setattr(
        viser.SceneApi, "configure_environment_map",
        lambda self, hdri="warehouse", **kw: calls.append(("env", hdri)),
    )  # fmt: skip
    monkeypatch.setattr(
        viser.SceneApi, "configure_default_lights",
        lambda self, enabled=True, cast_shadow=True: calls.append(("lights", enabled, cast_shadow)),
    )  # fmt: skip
    app = ViewerApp("radar", port=0, verbose=False)
    try:
        assert ("env", None) in calls and ("lights", True, False) in calls
    finally:
        app.stop()


def test_a_panel_callback_after_stop_does_nothing(app):
    if app.background is not None:  # its redraw would make the first call a skipped re-entry
        assert app.background.wait(60)
    runs = []
    callback = app.guard(lambda: runs.append(app.panel.refresh()))
    callback()
    app.stop()
    callback()
    assert len(runs) == 1 and app.panel.gate.closed and app.panel.gate is app.gate


def test_an_imported_model_opens_without_scipy_special(tmp_path):
    """Until the first picture of ``orientviz view FILE`` nothing loads scipy.special (with
    scipy's array-API layer ~0.2 s of the command's start, benchmarks/README.md "Session 18:
    the viewer's first picture"): the viewer's and the solver's modules, the evaluation of an
    imported model at its start values and its scene and panel (solved without the
    precision: no ellipsoid, no χ² quantile) leave it to the first use."""
    import subprocess
    import sys

    from orientviz.cli import main

    path = tmp_path / "axe.json"
    assert main(["import-colmap", "axe", "-o", str(path)]) == 0
    code = (
        "import sys\n"
        "from orientviz.viewer.app import resolve_content\n"
        f"demo = resolve_content({str(path)!r}, {{'free': True}}, background=True)\n"
        "assert demo.background is not None  # opens at the start values, solved later\n"
        "loaded = 'scipy.special' in sys.modules\n"
        "from orientviz.viewer.app import ViewerApp\n"
        "app = ViewerApp(demo, port=0, verbose=False, first_browser_wait=60)\n"
        "assert app.scene is not None and not app.messages\n"
        "print('scipy.special:', loaded, 'scipy.special' in sys.modules)\n"
        "app.stop()\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    (line,) = [x for x in out.stdout.splitlines() if x.startswith("scipy.special:")]
    assert line.split()[1:] == ["False", "False"]  # at the address; scene and panel built


def test_the_address_comes_before_the_scene_which_a_page_gets_whole(monkeypatch, capsys):
    """The page starts loading while the scene and the panel are built: the address is
    printed first, and the build runs inside the server's atomic block, so a page that
    connects meanwhile gets the scene and the panel in one batch, never half of them."""
    import viser

    from orientviz.viewer.scene import BlockScene

    seen = []
    build, atomic = BlockScene.build, viser.ViserServer.atomic
    depth = [0]

    def counted(self):
        depth[0] += 1
        try:
            with atomic(self):
                yield
        finally:
            depth[0] -= 1

    def recorded(scene):
        seen.append((capsys.readouterr().out, depth[0]))
        return build(scene)

    monkeypatch.setattr(viser.ViserServer, "atomic", contextlib.contextmanager(counted))
    monkeypatch.setattr(BlockScene, "build", recorded)
    app = ViewerApp("block", port=0, verbose=True)
    try:
        assert len(seen) == 1 and app.scene is not None
        printed, inside = seen[0]
        assert f"open {app.url}" in printed and inside == 1
        assert depth[0] == 0  # the batch is sent once the panel is built too
    finally:
        app.stop()
