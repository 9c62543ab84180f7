"""``orientviz view`` from the command line: export, Ctrl-C, the default demo."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import orientviz
from orientviz.cli import main

pytest.importorskip("viser")

SRC = str(Path(orientviz.__file__).resolve().parents[1])


def test_view_export_writes_static_html(tmp_path, capsys):
    out = tmp_path / "pair.html"
    assert main(["view", "pair", "--export", str(out)]) == 0
    html = out.read_text()
    assert "__VISER_EMBED_DATA__" in html and len(html) > 100_000
    assert f"wrote {out}" in capsys.readouterr().out


def test_view_unknown_demo_or_file_exits_2_on_export(tmp_path, capsys):
    assert main(["view", "nosuchdemo", "--export", str(tmp_path / "x.html")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "nosuchdemo" in err


def test_view_default_demo_prints_url_and_stops_on_ctrl_c():
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = dict(os.environ, PYTHONPATH=SRC + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen(
        [sys.executable, "-m", "orientviz.cli", "view", "--port", str(port)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        deadline = time.monotonic() + 60
        line = ""
        while time.monotonic() < deadline:
            line = proc.stdout.readline()
            if "orientviz viewer: open" in line or proc.poll() is not None:
                break
        assert f"http://127.0.0.1:{port}" in line
        time.sleep(0.5)
        proc.send_signal(signal.SIGINT)
        code = proc.wait(timeout=30)
        err = proc.stderr.read()
    finally:
        if proc.poll() is None:
            proc.kill()
    assert code == 0
    assert "Traceback" not in err
    assert "stopped" in err


def test_view_takes_solves_datum_options_free_and_fix(tmp_path, capsys):
    """`view FILE --free` solves as `solve FILE --free` (an imported SfM model has no control)."""
    from orientviz.io.solve import load_named, solve_problem
    from orientviz.viewer.app import demo_from_file

    problem = load_named("block_compact")
    problem.options = dict(problem.options, free=True)
    want = solve_problem(problem).adjustment
    demo = demo_from_file("block_compact", {"free": True})
    assert demo.solution.adjustment.sigma0 == pytest.approx(want.sigma0, rel=1e-9)
    assert demo.solution.adjustment.redundancy == want.redundancy
    plain = demo_from_file("block_compact").solution.adjustment
    assert plain.redundancy != want.redundancy  # the option changed the datum
    assert main(["view", "block_compact", "--free", "--export", str(tmp_path / "f.html")]) == 0
    assert main(["view", "block", "--free", "--export", str(tmp_path / "d.html")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--free" in err and "demo" in err
