"""The real ``python -m orientviz.cli`` in a subprocess with an address-space limit and a
timeout (the cases that would wedge or exhaust a test process if they regressed), and
``--debug``."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

from orientviz import cli

from . import inputs as I

SRC = str(Path(__file__).resolve().parents[2] / "src")
LIMIT = 1500 * 2**20  # bytes of address space for the whole interpreter


def _limits() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (LIMIT, LIMIT))


def _run(*argv: str, cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=SRC, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    return subprocess.run(
        [sys.executable, "-m", "orientviz.cli", *argv],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        preexec_fn=_limits,
    )


@pytest.mark.parametrize(
    ("what", "argv"),
    [
        ("fifo", lambda f: ["solve", str(f / "pipe.json")]),
        ("zero", lambda f: ["import-bal", str(f / "zero.bal"), "-o", str(f / "o.json")]),
        ("urandom", lambda f: ["view", str(f / "urandom.json"), "--export", str(f / "v.html")]),
        (
            "zero-csv",
            lambda f: [
                "import-bal",
                str(f / I.BAL),
                "--control",
                str(f / "z.csv"),
                "-o",
                str(f / "o.json"),
            ],
        ),  # fmt: skip
        ("zero-cameras", lambda f: ["import-colmap", str(f / "sparse"), "-o", str(f / "o.json")]),
    ],
)
def test_special_files_end_in_one_line_within_limits(what, argv, tmp_path):
    I.write(tmp_path, I.BAL, I.COLMAP)
    os.mkfifo(tmp_path / "pipe.json")
    (tmp_path / "zero.bal").symlink_to("/dev/zero")
    (tmp_path / "urandom.json").symlink_to("/dev/urandom")
    (tmp_path / "z.csv").symlink_to("/dev/zero")
    (tmp_path / "sparse" / "cameras.txt").unlink()
    (tmp_path / "sparse" / "cameras.txt").symlink_to("/dev/zero")
    before = sorted(p.name for p in tmp_path.rglob("*"))
    r = _run(*argv(tmp_path), cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    assert len(r.stderr.splitlines()) == 1, r.stderr
    assert "is a named pipe" in r.stderr or "is a device" in r.stderr, r.stderr
    assert sorted(p.name for p in tmp_path.rglob("*")) == before


def test_argument_errors_are_one_line_from_the_real_entry_point(tmp_path):
    r = _run("import-bal", "x.bal", "-o", "o.json", "--pixel-size", "nan", cwd=tmp_path)
    assert r.returncode == 2
    assert r.stderr.splitlines() == [
        "orientviz import-bal: argument --pixel-size: expected a finite number, got 'nan' "
        "(see orientviz import-bal --help)"
    ]


def _boom(args):
    raise RuntimeError("boom")


def test_an_unforeseen_error_is_one_line_and_debug_shows_the_traceback(monkeypatch, capsys):
    monkeypatch.setattr("orientviz.cli.run_reproduce", _boom)
    assert cli.main(["reproduce", "x"]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "internal error: RuntimeError: boom" in err
    with pytest.raises(RuntimeError, match="boom"):
        cli.main(["reproduce", "x", "--debug"])
