"""``orientviz --help`` lists every command with an example; every example parses and
the affordable ones run and succeed."""

from __future__ import annotations

import shlex
import shutil

import numpy as np
import pytest

from orientviz import cli
from orientviz.cli import COMMANDS, main

#: examples not run here, with the reason (each must still be one of the listed examples)
NOT_RUN = {
    "orientviz view": "serves until Ctrl-C (tests/viewer/test_cli.py runs it)",
    "orientviz view pair --port 8081": "serves until Ctrl-C",
    "orientviz view block.json": "serves until Ctrl-C",
    "orientviz reproduce geier": "takes ~7 s (tests/reproduce runs it)",
}


def _examples():
    return [(name, inv) for name, cmd in COMMANDS.items() for inv, _ in cmd.examples]


def _help(capsys, *argv: str) -> str:
    with pytest.raises(SystemExit) as exc:
        main([*argv, "--help"])
    assert exc.value.code == 0
    return capsys.readouterr().out


def test_top_level_help_lists_every_command_with_an_example(capsys):
    text = _help(capsys)
    lines = text.splitlines()
    for name, cmd in COMMANDS.items():
        row = [i for i, line in enumerate(lines) if line.split()[:1] == [name]]
        assert len(row) == 1, f"{name} is not listed once in orientviz --help"
        assert cmd.help in lines[row[0]]
        example = lines[row[0] + 1].strip()
        assert example.startswith(f"e.g. orientviz {name}"), example
        assert example.removeprefix("e.g. ") == cmd.examples[0][0]


@pytest.mark.parametrize("name", list(COMMANDS))
def test_command_help_has_examples(name, capsys):
    text = _help(capsys, name)
    assert "\nexamples:\n" in text
    shown = text.split("\nexamples:\n", 1)[1]
    for inv, what in COMMANDS[name].examples:
        assert any(
            line.split(inv, 1)[-1].strip() == what for line in shown.splitlines() if inv in line
        )


@pytest.mark.parametrize(("name", "invocation"), _examples())
def test_every_example_parses(name, invocation):
    words = shlex.split(invocation)
    assert words[0] == "orientviz"
    args = cli._parser().parse_args(words[1:])
    assert args.command == name


def test_not_run_list_names_real_examples():
    assert set(NOT_RUN) <= {inv for _, inv in _examples()}


@pytest.fixture
def inputs(tmp_path):
    """The files the examples name: block.json, a BAL file and a COLMAP model."""
    from orientviz.io.bal import write_bal
    from orientviz.io.colmap import write_colmap
    from orientviz.io.problem import problem_from_block, save_problem
    from orientviz.simulate import simulate_block

    folder = tmp_path / "inputs"
    folder.mkdir()
    block = simulate_block(1, 5, rng=7, control="full").block
    save_problem(problem_from_block(block), folder / "block.json")
    write_bal(block, folder / "problem-49-7776-pre.txt")
    write_colmap(block, folder / "sparse" / "0", pixel_size_mm=0.01)
    obs = block.observations  # import-csv: a measurement table in pixels and a control CSV
    rows = ["image,point,x,y"] + [
        f"{block.images.ids[i]},{block.points.ids[p]},{x / 0.006},{-y / 0.006}"
        for i, p, (x, y) in zip(obs.image, obs.point, obs.xy)
    ]
    (folder / "marks.csv").write_text("\n".join(rows) + "\n")
    ctrl = ["id,X,Y,Z"] + [
        f"{block.points.ids[k]},{X},{Y},{Z}"
        for k, (X, Y, Z) in enumerate(block.points.xyz_known)
        if np.all(np.isfinite((X, Y, Z)))
    ]
    (folder / "control.csv").write_text("\n".join(ctrl) + "\n")
    return folder


def test_affordable_examples_run(inputs, tmp_path, monkeypatch, capsys):
    ran = []
    for k, (name, invocation) in enumerate(_examples()):
        if invocation in NOT_RUN:
            continue
        if name == "view":
            pytest.importorskip("viser")
        cwd = shutil.copytree(inputs, tmp_path / f"run{k}")  # each example on fresh inputs
        monkeypatch.chdir(cwd)
        words = shlex.split(invocation)[1:]
        made = [w for w in words if w.endswith((".json", ".html")) and not (cwd / w).exists()]
        code = main(words)
        out, err = capsys.readouterr()
        assert code == 0, f"{invocation}: exit {code}: {err}"
        assert out.strip(), f"{invocation} printed nothing"
        for w in made:  # the files an example says it writes are there
            assert (cwd / w).stat().st_size > 0, f"{invocation} did not write {w}"
        ran.append(invocation)
    assert len(ran) + len(NOT_RUN) == len(_examples())
