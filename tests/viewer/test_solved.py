"""The viewer solves a problem file exactly as ``orientviz solve`` does (issue 31, points 1, 6)."""

import json

import numpy as np
import pytest

from orientviz.cli import main
from orientviz.io.datasets import list_datasets
from orientviz.viewer.app import ViewerApp, resolve_content

pytest.importorskip("viser")

BLOCKS = ("block_strip", "block_compact", "dbat_sxb", "dbat_camcal")


def solve_json(name, capsys):
    assert main(["solve", name, "--json"]) in (0, 3, 4)
    return json.loads(capsys.readouterr().out)


@pytest.mark.parametrize("name", BLOCKS)
def test_sigma0_and_iterations_are_the_solves(name, capsys):
    want = solve_json(name, capsys)
    demo = resolve_content(name)
    st = demo.state
    assert abs(st.sigma0() - want["sigma0"]) < 1e-9
    assert abs(st.result.sigma0 - want["sigma0"]) < 1e-9
    # every iteration from the approximations is on the scrubber
    assert len(st.history) == want["iterations"] + 1
    assert st.history[0].label == "start"
    st.replay(0)
    np.testing.assert_array_equal(st.block.images.X0, demo.solution.start.images.X0)
    assert np.all(np.isfinite(st.block.images.X0))  # dbat_sxb: approximations computed
    assert st.sigma0() == pytest.approx(st.result.history[0].sigma0, rel=1e-12)
    st.replay(len(st.history) - 1)
    assert abs(st.sigma0() - want["sigma0"]) < 1e-9


def test_panel_prints_the_solves_sigma0(capsys):
    want = solve_json("dbat_camcal", capsys)["sigma0"]
    app = ViewerApp("dbat_camcal", port=0, verbose=False)
    try:
        text = app.panel.handles["stats"].content
        shown = float(text.split("last adjustment: σ̂0 = ")[1].split(",")[0])
        assert abs(shown - want) < 1e-9
        assert "strip -1" not in app.panel.handles["image_id"].content
    finally:
        app.stop()


def test_camera_model_misclosure_is_the_bundles():
    """dbat_camcal: the drawn misclosure at the result is −v of the bundle (lens terms in)."""
    st = resolve_content("dbat_camcal").state
    assert st.camera is not None and st.ap is not None
    n = st.block.n_observations
    v = st.result.residuals[: 2 * n].reshape(n, 2)
    np.testing.assert_allclose(st.misclosure(), -v, atol=1e-12)
    # without the camera terms (the pinhole of the file's c, x0, y0) it is not
    assert np.max(np.abs(st.block.residuals() + v)) > 1e-3


@pytest.mark.parametrize("name", list_datasets())
def test_view_accepts_every_name_solve_accepts(name):
    demo = resolve_content(name)
    assert demo.solution is not None
    assert demo.state is not None or demo.extra is not None


def test_act_on_camcal_resolves_with_the_lens_model():
    """A ray off: the re-solve estimates the camera as the file says (same optimum as a
    cold solve of the file without that ray)."""
    from orientviz.io.solve import load_named, solve_problem

    st = resolve_content("dbat_camcal").state
    j = 17
    st.toggle_observation(j, precision=False)
    assert "additional" in st.result.groups
    problem = load_named("dbat_camcal")
    keep = np.ones(problem.data.n_observations, bool)
    keep[j] = False
    problem.data = problem.data.take(None, None, np.flatnonzero(keep))
    cold = solve_problem(problem).adjustment
    assert st.result.sigma0 == pytest.approx(cold.sigma0, rel=1e-6)
    assert st.result.sigma0 != pytest.approx(1.6148043484895638, rel=1e-6)


BAD = {
    "missing.json": None,
    "nosuchname": None,
    "broken.json": "{not json",
    "wrongkind.json": json.dumps({"format": "orientviz/1", "kind": "nokind"}),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_input_same_line_and_code_as_solve_before_any_server(name, tmp_path, monkeypatch,
                                                                 capsys):  # fmt: skip
    import viser

    path = tmp_path / name
    if BAD[name] is not None:
        path.write_text(BAD[name])
    target = str(path) if name.endswith(".json") else name
    code_solve = main(["solve", target])
    err_solve = capsys.readouterr().err

    def no_server(*a, **k):
        raise AssertionError("a server was started for a file that cannot be solved")

    monkeypatch.setattr(viser, "ViserServer", no_server)
    code_view = main(["view", target])
    err_view = capsys.readouterr().err
    assert code_view == code_solve != 0
    assert err_view.count("\n") == 1
    assert err_view.replace("orientviz view:", "") == err_solve.replace("orientviz solve:", "")


def test_datum_defect_exits_3_like_solve(tmp_path, capsys, monkeypatch):
    import viser

    from orientviz.io.problem import save_problem
    from orientviz.io.solve import load_named

    problem = load_named("block_strip")
    problem.data.points.role[:] = 0  # no control: a datum defect
    problem.data.points.xyz_known[:] = np.nan
    path = tmp_path / "defect.json"
    save_problem(problem, path)
    code_solve = main(["solve", str(path)])
    err_solve = capsys.readouterr().err
    monkeypatch.setattr(viser, "ViserServer", lambda *a, **k: pytest.fail("server started"))
    assert main(["view", str(path)]) == code_solve == 3
    # the same message; its program name and the hint's command line name the command run
    err_view = capsys.readouterr().err
    assert "orientviz view " in err_view and "--free" in err_view
    assert (
        err_view.replace("view:", "solve:").replace("orientviz view ", "orientviz solve ")
        == err_solve
    )


def test_not_converged_opens_with_message_and_last_state(tmp_path):
    from orientviz.io.problem import save_problem
    from orientviz.io.solve import load_named

    problem = load_named("block_compact")
    problem.options = dict(problem.options, max_iter=1)
    path = tmp_path / "short.json"
    save_problem(problem, path)
    assert main(["solve", str(path)]) == 3
    app = ViewerApp(str(path), port=0, verbose=False)
    try:
        assert any("did not converge" in m for m in app.messages)
        st = app.demo.state
        assert st.cursor == len(st.history) - 1 == 1
        assert np.all(np.isfinite(st.block.images.X0)) and np.all(np.isfinite(st.block.points.xyz))
    finally:
        app.stop()


def test_bad_host_is_not_a_busy_port(capsys):
    assert main(["view", "pair", "--host", "256.1.1.1", "--port", "0"]) == 2
    err = capsys.readouterr().err
    assert "256.1.1.1" in err and "already in use" not in err
