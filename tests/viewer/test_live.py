"""The viewer live in a lesson (orientviz.viewer.live): what the notebook gets, headless.

No browser here (tests/integration/test_jupyterlab.py opens a lesson in JupyterLab
and sees the scene); these tests check the output a lesson cell displays, that the server
listens on 127.0.0.1 only, and that the lesson scenes hold the student's states.
"""

from __future__ import annotations

import socket

import numpy as np
import pytest

pytest.importorskip("viser")
pytest.importorskip("IPython")

import orientviz as ov  # noqa: E402
from orientviz.viewer import live  # noqa: E402


@pytest.fixture(scope="module")
def small_block():
    sim = ov.simulate_block(2, 4, rng=3, extra=None)
    return sim


def test_show_live_displays_an_iframe_with_the_snapshot_name(monkeypatch, capsys):
    shown = []
    monkeypatch.setattr(
        "IPython.display.display", lambda obj, **kw: shown.append((obj, kw)), raising=True
    )
    app = live.show_live("radar", snapshot="14_test", height=333)
    try:
        assert app.host == "127.0.0.1" and app.port > 0
        ((data, kw),) = shown
        assert kw["raw"] is True and kw["metadata"] == {live.SNAPSHOT_KEY: "14_test"}
        html = data["text/html"]
        assert f'src="http://127.0.0.1:{app.port}"' in html and 'height="333"' in html
        assert app.url in data["text/plain"]
        # nothing of viser's start-up banner reaches the cell's output
        out = capsys.readouterr()
        assert "Websocket" not in out.out + out.err
        # the server answers on 127.0.0.1 ...
        with socket.create_connection(("127.0.0.1", app.port), timeout=5):
            pass
        # ... and on no other interface of this machine
        others = {
            a[4][0]
            for a in socket.getaddrinfo(socket.gethostname(), None, socket.AF_INET)
            if not a[4][0].startswith("127.")
        }
        for addr in others:
            with pytest.raises(OSError):
                socket.create_connection((addr, app.port), timeout=2).close()
    finally:
        app.stop()


def test_iterations_demo_replays_the_given_states(small_block):
    blk = small_block.block
    truth = small_block.truth
    states = [
        (blk.images.X0 + 0.5, blk.images.angles, blk.points.xyz, 9.0),
        (blk.images.X0 + 0.1, blk.images.angles, blk.points.xyz, 2.0),
        (truth.images.X0, truth.images.angles, truth.points.xyz, 1.0),
    ]
    demo = live.iterations_demo(blk, states, "mine")
    st = demo.state
    assert [s.label for s in st.history] == ["start", "iteration 1", "iteration 2"]
    assert st.cursor == 2
    np.testing.assert_array_equal(st.block.images.X0, truth.images.X0)
    st.replay(0)
    np.testing.assert_array_equal(st.block.images.X0, blk.images.X0 + 0.5)
    assert st.history[1].sigma0 == 2.0
    with pytest.raises(ValueError):
        live.iterations_demo(blk, [])
    app = live.start(demo)
    try:
        panel = app.panel
        assert int(panel.handles["iteration"].max) == 2  # the scrubber covers the states
        panel.replay(1)
        np.testing.assert_array_equal(app.demo.state.block.images.X0, blk.images.X0 + 0.1)
    finally:
        app.stop()


def test_pair_passes_demo_sets_the_dials_to_the_passes():
    from orientviz.orientation.plotter import config_with, true_pair

    pair = true_pair(
        config_with(sequence="opk", sigma_by=0.0, sigma_z=0.0), rng=np.random.default_rng(1)
    )
    passes = [np.zeros(5), 0.5 * pair.elements, pair.elements]
    app = live.start(live.pair_passes_demo(pair, passes))
    try:
        view = app.extra["pair"]
        np.testing.assert_allclose(view.plotter.settings, pair.elements)
        assert len(view.snapshots) == 3 and int(view.h["scrub"].max) == 2
        view.h["scrub"].value = 1  # the scrubber replays the second pass
        np.testing.assert_allclose(view.plotter.settings, 0.5 * pair.elements)
        live.set_pair_dials(app, 0.25 * pair.elements)  # the notebook turns the dials
        np.testing.assert_allclose(view.plotter.settings, 0.25 * pair.elements)
        assert float(view.h["kappa [c]"].value) == pytest.approx(
            0.25 * pair.elements[4] * 200 / np.pi * 100, abs=0.01
        )
        pts = live.mark_points(app, "/pair/mine", np.zeros((2, 3)))
        np.testing.assert_allclose(pts.points, view.frame.to_scene(np.zeros((2, 3))), atol=1e-3)
    finally:
        app.stop()


def test_deformation_demo_shows_the_errors_against_the_truth(small_block):
    blk, truth = small_block.block, small_block.truth
    adj = ov.bundle_adjust(blk)
    app = live.start(live.deformation_demo(blk, adj, truth))
    try:
        ctl = app.extra["deformation"]
        ctl["show"].value = True
        vec = app.extra["deformation_nodes"][0]
        assert vec.visible and vec.points.shape[0] == blk.n_points
        import re

        shown = float(re.search(r"at t = 1: ([0-9.eE+-]+) m", ctl["info"].content).group(1))
        d = adj.x[adj.groups["points"]].reshape(-1, 3) - truth.points.xyz
        assert shown == pytest.approx(np.linalg.norm(np.sqrt(np.mean(d**2, axis=0))), rel=5e-3)
    finally:
        app.stop()


def test_pair_read_out_says_where_the_dials_stand_against_the_scrubber():
    """Lesson 05's snapshot read "passes: 0" (the plotter's own counter) beside the
    scrubber at pass 5, with the dials turned 2 c away from that pass by the notebook."""
    from orientviz.orientation.plotter import config_with, true_pair
    from orientviz.units import RHO_C

    pair = true_pair(
        config_with(sequence="opk", sigma_by=0.0, sigma_z=0.0), rng=np.random.default_rng(1)
    )
    passes = [np.zeros(5), 0.5 * pair.elements, 0.9 * pair.elements, pair.elements]
    app = live.start(live.pair_passes_demo(pair, passes))
    try:
        view = app.extra["pair"]
        assert int(view.h["scrub"].value) == 3
        assert "dials at pass 3 of 3" in view.h["stats"].content
        assert "turned" not in view.h["stats"].content
        live.set_pair_dials(app, pair.elements + np.r_[0, 0, 0, 0, 2.0 / RHO_C])
        stats = view.h["stats"].content
        assert "dials at pass 3 of 3, turned by κ +2.0 c" in stats and "passes: 0" not in stats
        view.h["scrub"].value = 1
        assert "dials at pass 1 of 3" in view.h["stats"].content
        assert "turned" not in view.h["stats"].content
        view.h["by [mm]"].value = round(float(view.h["by [mm]"].value) + 0.5, 2)  # by hand
        # the other dials snap to the sliders' steps: less than half a step is no turn
        assert "dials at pass 1 of 3, turned by by +0.50" in view.h["stats"].content
        assert "bz" not in view.h["stats"].content.split("\n")[1]
    finally:
        app.stop()
