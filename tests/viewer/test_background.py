"""A large imported model opens before its solve ends (issue 28 point 7).

A COLMAP model (simulated 2 × 5 block written by ``write_colmap``, read back by
``orientviz import-colmap``; every start value given) with the viewer's size limit
lowered below its 566 image points: ``orientviz view`` shows it at the file's start
values — σ0 and residuals through the solve's own model — while the solve runs in a
thread; then the viewer takes the solution, which equals ``solve``'s. The solve is held
at a gate so that the state "while solving" is seen every time.
"""

from __future__ import annotations

import threading

import numpy as np
import pytest

from orientviz.cli import main
from orientviz.errors import AdjustmentError, InputError
from orientviz.io.solve import load_named
from orientviz.viewer import app as app_module
from orientviz.viewer import solved
from orientviz.viewer.app import ViewerApp, resolve_content
from orientviz.viewer.background import BackgroundSolve, Cancelled


@pytest.fixture(scope="module")
def model(tmp_path_factory) -> str:
    from orientviz.io.colmap import write_colmap
    from orientviz.simulate import simulate_block

    folder = tmp_path_factory.mktemp("colmap")
    write_colmap(simulate_block(2, 5, rng=1).block, folder / "model")
    path = folder / "model.json"
    assert main(["import-colmap", str(folder / "model"), "-o", str(path)]) == 0
    return str(path)


@pytest.fixture(scope="module")
def reference(model):
    """``orientviz solve``'s solution of the model (as a free network)."""
    return solved.solve_target(model, {"free": True}).solution


@pytest.fixture
def small_limit(monkeypatch):
    monkeypatch.setattr(solved, "PRECISION_LIMIT", 100)


def gated(demo):
    """Hold the demo's background solve until the returned event is set."""
    gate, solve = threading.Event(), demo.background.solve

    def held(callback):
        assert gate.wait(60)
        return solve(callback)

    demo.background.solve = held
    return gate


def test_opens_at_the_start_values_and_takes_the_solution_of_solve(model, reference, small_limit):
    ref = reference.adjustment
    demo = resolve_content(model, {"free": True}, background=True)
    assert demo.background is not None and demo.state.pending
    gate = gated(demo)
    app = ViewerApp(demo, port=0, verbose=False)
    try:
        p = app.panel
        st = p.state
        # while solving: the file's start values, σ0 and |v|/σ of the solve's first record
        np.testing.assert_array_equal(st.block.points.xyz, reference.start.points.xyz)
        assert st.sigma0() == pytest.approx(ref.history[0].sigma0, rel=1e-9)
        assert st.scores()[1] == "|v|/σ"
        assert "solving in the background" in p.handles["stats"].content
        assert "being solved" in app._head.content
        with pytest.raises(InputError, match="still running"):
            p.act.toggle_image()
        k0 = app.scene.exaggeration
        start_vectors = np.linalg.norm(np.diff(app.scene.geo.residuals(k0)[0], axis=1), axis=2)
        gate.set()
        assert app.background.wait(60)
        # the solution: solve's σ̂0 and iterations, the residual scale kept
        assert st.pending is None and not app.messages
        assert st.result.sigma0 == pytest.approx(ref.sigma0, rel=1e-9)
        assert len(st.history) == len(ref.history) and st.cursor == len(ref.history) - 1
        assert [c.label for c in st.changes] == ["as adjusted"]
        stats = p.handles["stats"].content
        assert "solving" not in stats and f"{ref.sigma0:.10g}" in stats
        assert "being solved" not in app._head.content and "solved by bundle" in app._head.content
        assert app.scene.exaggeration == k0
        end_vectors = np.linalg.norm(np.diff(app.scene.geo.residuals(k0)[0], axis=1), axis=2)
        assert np.median(end_vectors) < 0.1 * np.median(start_vectors)  # they shrank
        # the start is on the scrubber: replaying it gives the start values again
        p.replay(0)
        assert st.sigma0() == pytest.approx(ref.history[0].sigma0, rel=1e-9)
        p.replay(len(st.history) - 1)
        # actions now re-solve, and undo restores the solution
        p.act.toggle_image()
        assert len(st.changes) == 2 and st.result.sigma0 != pytest.approx(ref.sigma0)
        p.act.undo()
        assert st.result.sigma0 == pytest.approx(ref.sigma0, rel=1e-9)
    finally:
        app.stop()


def test_a_failing_background_solve_is_shown_as_solve_reports_it(model, small_limit):
    demo = resolve_content(model, {"free": True}, background=True)
    gate = gated(demo)
    inner = demo.background.solve

    def fails(callback):
        inner(callback)
        raise AdjustmentError("reduced normal equations singular")

    demo.background.solve = fails
    app = ViewerApp(demo, port=0, verbose=False)
    try:
        gate.set()
        assert app.background.wait(60)
        assert app.panel.state.pending is None
        assert len(app.messages) == 1 and "reduced normal equations singular" in app.messages[0]
        assert "solving" not in app.panel.handles["stats"].content
    finally:
        app.stop()


def test_stopping_the_viewer_stops_the_solve_between_iterations():
    done, started = [], threading.Event()

    def solve(callback):
        for k in range(10_000):
            callback(type("It", (), {"index": k, "sigma0": 1.0})())
            started.set()
            threading.Event().wait(0.005)
        return "finished"

    job = BackgroundSolve(solve, shown=2.0)
    job.start(done.append)
    assert started.wait(10)
    assert "iteration" in job.status() and "σ̂0 2" in job.status()
    job.cancel()
    job._thread.join(10)
    assert not job._thread.is_alive() and job.result is None and done == []


def test_only_large_blocks_with_every_start_value_open_before_the_solve(model, small_limit):
    problem = load_named(model)
    assert solved.opens_before_solve(problem)
    problem.data.points.xyz[3, 2] = np.nan
    assert not solved.opens_before_solve(problem)
    solved.PRECISION_LIMIT = 10_000  # (monkeypatched: restored after the test)
    assert not solved.opens_before_solve(load_named(model))
    assert resolve_content(model, {"free": True}, background=True).background is None


def test_a_snapshot_shows_the_solution(model, reference, small_limit, tmp_path):
    demo = resolve_content(model, {"free": True}, background=True)
    out = app_module.export_html(demo, tmp_path / "view.html")
    text = out.read_text(encoding="utf-8")
    assert f"{reference.adjustment.sigma0:.10g}" in text and "solving" not in text


def test_a_solution_ending_in_nan_shows_its_last_finite_state(model, small_limit):
    """Never a blank canvas: as when a file is solved before the server starts."""
    demo = resolve_content(model, {"free": True}, background=True)
    inner = demo.background.solve

    def poisoned(callback):
        out = inner(callback)
        adj = out.solution.adjustment
        pts = adj.groups["points"]
        adj.x = np.array(adj.x, float)
        adj.x[pts] = np.nan  # the estimate (and its last record) thrown to NaN
        adj.history[-1].x = adj.x
        return out

    demo.background.solve = poisoned
    app = ViewerApp(demo, port=0, verbose=False)
    try:
        assert app.background.wait(60)
        st = app.panel.state
        assert np.isfinite(st.block.points.xyz).all()
        assert st.cursor == len(st.history) - 2
    finally:
        app.stop()


def test_a_hold_pauses_the_solve_at_its_next_iteration():
    """A browser connecting holds the solve (its first picture gets the CPU)."""
    job = BackgroundSolve(lambda callback: None, shown=1.0)
    job.hold(60.0)
    waiting = threading.Thread(target=lambda: pytest.raises(Cancelled, job._progress, "it", None))
    waiting.start()
    waiting.join(0.3)
    assert waiting.is_alive() and job.iteration is None  # held at the iteration's end
    job.cancel()  # stopping the viewer ends a hold too
    waiting.join(10)
    assert not waiting.is_alive()
    free = BackgroundSolve(lambda callback: None, shown=1.0)
    free._progress("it", None)  # no hold: goes on at once
    assert free.iteration == "it"


def test_orientviz_view_begins_the_solve_after_a_first_browser_has_had_its_picture():
    """``first_browser_wait``: the solve begins when the hold of a browser that connected
    meanwhile has passed, or after the wait if none comes."""
    began = threading.Event()
    order: list[str] = []

    def solve(callback):
        order.append("solve")
        began.set()

    job = BackgroundSolve(solve, shown=1.0)
    job.start(lambda j: None, wait=60.0)
    assert not began.wait(0.3)  # no browser yet: waiting
    order.append("browser")
    job.hold(0.2)  # a browser connects: its picture first
    assert began.wait(30) and order == ["browser", "solve"]
    assert job.wait(30)

    alone = BackgroundSolve(solve, shown=1.0)  # nobody comes: it begins after the wait
    began.clear()
    alone.start(lambda j: None, wait=0.1)
    assert began.wait(30) and alone.wait(30)

    stopped = BackgroundSolve(solve, shown=1.0)  # stopping the viewer while it waits
    began.clear()
    stopped.start(lambda j: None, wait=60.0)
    stopped.cancel()
    stopped._thread.join(30)
    assert not stopped._thread.is_alive() and not began.is_set()
