"""Solver options on the command line, messages in the user's ids, full precision in --json."""

from __future__ import annotations

import json

from orientviz.cli import main
from orientviz.io.datasets import load_dataset
from orientviz.io.kinds.block import solve


def test_max_iter_on_the_command_line_overrides_the_file(capsys):
    assert main(["solve", "dbat_sxb", "--max-iter", "1", "--json"]) == 3
    doc = json.loads(capsys.readouterr().out)
    assert doc["iterations"] == 1 and not doc["converged"]
    assert main(["solve", "dbat_sxb", "--tol", "1e-7", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["iterations"] > 4 and doc["converged"]


def test_json_carries_sigma0_in_full_precision(capsys):
    assert main(["solve", "dbat_sxb", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    sol = solve(load_dataset("dbat_sxb"), "bundle")
    assert doc["sigma0"] == sol.adjustment.sigma0  # not rounded to 4 or 6 digits
    assert len(repr(doc["sigma0"])) > 10


def test_control_pseudo_observations_are_named_by_point_and_coordinate():
    sol = solve(load_dataset("dbat_sxb"), "bundle")
    labels = sol.adjustment.obs_labels
    assert not [lab for lab in labels if "pseudo" in lab or lab.startswith("observation ")]
    assert "492/X" in labels and "8811/317/x" in labels
    assert sum(lab.endswith(("/X", "/Y", "/Z")) for lab in labels) == 42  # 14 control × 3
