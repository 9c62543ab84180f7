"""``orientviz solve FILE --report PATH``: formats by suffix, exit codes, one-line errors."""

from __future__ import annotations

import json

import pytest

import orientviz as ov
from orientviz.cli import main
from orientviz.io.datasets import resolve_name


def run(capsys, *argv: str) -> tuple[int, str, str]:
    rc = main(list(argv))
    out = capsys.readouterr()
    return rc, out.out, out.err


@pytest.mark.parametrize("suffix", [".html", ".txt"])
def test_report_is_written_and_stdout_unchanged(tmp_path, capsys, suffix):
    path = tmp_path / f"report{suffix}"
    rc, out, err = run(capsys, "solve", "resection_example", "--report", str(path))
    assert rc == 0 and err.startswith(f"orientviz solve: wrote {path} (") and err.count("\n") == 1
    assert out.startswith("resection (resection):")  # the usual report is still printed
    text = path.read_text(encoding="utf-8")
    assert "Per-image precision" in text and "Largest normalised residuals" in text
    assert text.lstrip().startswith("<!DOCTYPE html>") == (suffix == ".html")


def test_json_output_with_report(tmp_path, capsys):
    rc, out, _ = run(capsys, "solve", "block_strip", "--json", "--report", str(tmp_path / "r.txt"))
    assert rc == 0
    assert json.loads(out)["kind"] == "block"
    assert "Check-point statistics" in (tmp_path / "r.txt").read_text(encoding="utf-8")


@pytest.mark.parametrize(
    "target",
    ["missing-folder/report.html", "report.pdf", "report", "."],
    ids=["no-folder", "bad-suffix", "no-suffix", "directory"],
)
def test_bad_report_path_is_one_line_and_exit_2(tmp_path, capsys, target):
    path = tmp_path / target if target != "." else tmp_path
    if target == ".":
        path = tmp_path / "dir.html"
        path.mkdir()
    rc, _, err = run(capsys, "solve", "block_strip", "--report", str(path))
    assert rc == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("orientviz solve: ") and str(path) in lines[0]
    assert "Traceback" not in err
    assert not (tmp_path / "missing-folder").exists()


def test_not_converged_still_writes_the_report_and_exits_3(tmp_path, capsys):
    problem = ov.load_problem(resolve_name("block_compact"))
    problem.options["max_iter"] = 1
    src = ov.save_problem(problem, tmp_path / "one_step.json")
    report = tmp_path / "r.txt"
    rc, _, err = run(capsys, "solve", str(src), "--report", str(report))
    assert rc == 3
    assert "did not converge" in err
    text = report.read_text(encoding="utf-8")
    assert "NOT CONVERGED" in text and "did not converge" in text
