"""``orientviz solve --solver`` and ``options.solver``: the reduced-system solver, named in the report."""

from __future__ import annotations

import json

from orientviz.cli import main
from orientviz.io.datasets import load_dataset
from orientviz.io.problem import save_problem


def _note(doc: dict) -> str:
    notes = [n for n in doc["notes"] if n.startswith("reduced system solved")]
    assert len(notes) == 1
    return notes[0]


def test_solver_on_the_command_line_is_used_and_named(capsys):
    sigma0 = {}
    for solver in ("banded", "dense", "sparse"):
        assert main(["solve", "block_strip", "--solver", solver, "--json"]) == 0
        doc = json.loads(capsys.readouterr().out)
        how = ", nested-dissection multifrontal Cholesky" if solver == "sparse" else ""
        assert _note(doc) == f"reduced system solved {solver} (requested{how})"
        sigma0[solver] = doc["sigma0"]
    # the same optimum whatever factors the reduced system
    assert abs(sigma0["dense"] - sigma0["banded"]) < 1e-9 * sigma0["banded"]
    assert abs(sigma0["sparse"] - sigma0["banded"]) < 1e-9 * sigma0["banded"]
    assert main(["solve", "block_strip", "--json"]) == 0
    assert "(auto: 4 images" in _note(json.loads(capsys.readouterr().out))


def test_solver_in_the_problem_file_and_its_checks(tmp_path, capsys):
    problem = load_dataset("block_strip")
    problem.options = dict(problem.options, solver="sparse")
    path = tmp_path / "strip.json"
    save_problem(problem, path)
    assert main(["solve", str(path), "--json"]) == 0
    assert _note(json.loads(capsys.readouterr().out)).startswith("reduced system solved sparse")
    # the command line wins over the file
    assert main(["solve", str(path), "--solver", "banded", "--json"]) == 0
    assert _note(json.loads(capsys.readouterr().out)).startswith("reduced system solved banded")
    doc = json.loads(path.read_text())
    doc["options"]["solver"] = "splu"
    path.write_text(json.dumps(doc))
    assert main(["solve", str(path)]) == 2
    assert "solver" in capsys.readouterr().err
    assert main(["solve", "resection_example", "--solver", "dense"]) == 2
    assert "block problems only" in capsys.readouterr().err
