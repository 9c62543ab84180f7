"""The cyclic garbage collector in a command's own process (``cli.pause_collector``).

A one-shot command's process runs without Python's cyclic collector; a command that
serves until it is stopped (``view``) keeps it, and so does a call of ``main`` from
Python (a test, a notebook).
"""

from __future__ import annotations

import gc
import os
import subprocess
import sys

import pytest

from orientviz.cli import COMMANDS, main, pause_collector

#: The command's own process (``main()`` without argv, as the console script runs it):
#: an exit handler reports whether the collector is on when the command has finished.
_RUN = (
    "import atexit, gc, sys\n"
    "atexit.register(lambda: print('collector on:', gc.isenabled(), file=sys.stderr))\n"
    "from orientviz.cli import main\n"
    "sys.argv = ['orientviz', *sys.argv[1:]]\n"
    "main()\n"
)


def _collector_at_exit(*argv: str, cwd) -> tuple[bool, int]:
    r = subprocess.run(
        [sys.executable, "-c", _RUN, *argv],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=dict(os.environ, MPLBACKEND="Agg"),
        timeout=300,
    )
    line = [s for s in r.stderr.splitlines() if s.startswith("collector on:")]
    assert len(line) == 1, r.stderr
    return line[0].endswith("True"), r.returncode


@pytest.fixture
def collector_restored():
    """Leave the collector as the test found it."""
    was = gc.isenabled()
    yield
    if was:
        gc.enable()
    else:  # pragma: no cover - the suite runs with the collector on
        gc.disable()


def test_a_solve_in_its_own_process_runs_without_the_collector(tmp_path):
    on, code = _collector_at_exit("solve", "dbat_camcal", cwd=tmp_path)
    assert code == 0
    assert not on


def test_a_failing_command_in_its_own_process_also_runs_without_it(tmp_path):
    on, code = _collector_at_exit("solve", "no_such_file.json", cwd=tmp_path)
    assert code == 2
    assert not on


def test_main_called_from_python_keeps_the_collector(tmp_path, collector_restored, capsys):
    gc.enable()
    assert main(["solve", str(tmp_path / "no_such_file.json")]) == 2
    assert gc.isenabled()


def test_only_the_server_keeps_the_collector(collector_restored):
    serving = {name for name, cmd in COMMANDS.items() if cmd.serves}
    assert serving == {"view"}
    for name in COMMANDS:
        gc.enable()
        pause_collector(name)
        assert gc.isenabled() == (name in serving), name


def test_an_unknown_command_name_leaves_the_collector_alone(collector_restored):
    gc.enable()
    pause_collector("no-such-command")
    assert gc.isenabled()
