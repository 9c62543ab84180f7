"""Counts add up in every output of ``orientviz solve`` (issue #14 point 7).

n − u = r in the first line of the text report, in ``--json`` and in the adjustment
report's summary; n and u are recounted here from the block's tables (rays, roles,
weighted control) instead of trusting the solver's counters.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

import orientviz as ov
from orientviz.block import CHECK, CONTROL, TIE
from orientviz.cli import main
from orientviz.io.datasets import dataset_path
from orientviz.io.kinds.block import check_mode
from orientviz.report import build_report


def recount(problem) -> tuple[int, int]:
    """n, u of a bundle from the block's tables: adjusted rays (x, y), weighted control
    coordinates; six per image, three per unknown point."""
    block: ov.Block = problem.data
    role = block.points.role.copy()
    if check_mode(problem) == "rays":
        role[role == CHECK] = TIE
    rays = np.bincount(block.observations.point[role[block.observations.point] != CHECK],
                       minlength=block.n_points)  # fmt: skip
    weighted = (
        (role == CONTROL)[:, None] & (block.points.sigma > 0) & np.isfinite(block.points.sigma)
    )
    if problem.options.get("control") == "fixed":
        weighted[:] = False
    ctrl_unknown = (role == CONTROL) & weighted.any(axis=1) & (rays > 0)
    n = 2 * int(rays.sum()) + int(weighted[ctrl_unknown].sum())
    u = 6 * block.n_images + 3 * int(np.sum(role == TIE) + ctrl_unknown.sum())
    return n, u


def outputs(
    capsys, path: str, *argv: str, method: str | None = None
) -> tuple[dict, tuple[int, int, int], dict]:
    """(--json counts, first-line counts of the text report, report summary values)."""
    assert main(["solve", path, "--json", *argv]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert main(["solve", path, *argv]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    m = re.search(r": (\d+) observations, (\d+) unknowns, redundancy (\d+)", first)
    assert m, first
    problem = ov.load_problem(path)
    solution = ov.solve_problem(problem, method)
    summary = build_report(problem, solution).section("summary").values
    return doc, tuple(int(g) for g in m.groups()), summary


@pytest.mark.parametrize("mode", ["independent", "rays"])
def test_dbat_sxb_counts_add_up_both_check_modes(mode, capsys, tmp_path):
    doc = json.loads(Path(dataset_path("dbat_sxb")).read_text())
    doc["options"]["check_points"] = mode
    path = tmp_path / "sxb.json"
    path.write_text(json.dumps(doc))
    out, line, summary = outputs(capsys, str(path))
    n, u = recount(ov.load_problem(str(path)))
    assert (out["observations"], out["unknowns"]) == (n, u)
    assert out["observations"] - out["unknowns"] == out["redundancy"]
    assert line == (n, u, out["redundancy"])
    assert (summary["observations"], summary["unknowns"], summary["redundancy"]) == line
    # what is reported but was not adjusted: the check rays (x, y) in independent mode
    block = ov.load_problem(str(path)).data
    check_rays = int(np.sum(block.points.role[block.observations.point] == CHECK))
    expect = 2 * check_rays if mode == "independent" else 0
    assert out["not_adjusted"]["observations"] == expect == summary["excluded"]


def test_block_strip_fixed_control_counts(capsys):
    path = str(dataset_path("block_strip"))
    out, line, summary = outputs(capsys, path)
    assert (out["observations"], out["unknowns"]) == recount(ov.load_problem(path))
    assert line == (out["observations"], out["unknowns"], out["redundancy"])
    assert out["conditions"] == 0
    assert (summary["observations"], summary["unknowns"], summary["redundancy"]) == line
    # fixed control and check points are reported (with their coordinates) but not unknowns
    block = ov.load_problem(path).data
    reported = 6 * block.n_images + 3 * block.n_points
    assert out["unknowns"] + out["not_adjusted"]["parameters"] == reported


def test_models_counts_add_up(capsys):
    path = str(dataset_path("block_compact"))
    out, line, summary = outputs(capsys, path, "--method", "models", method="models")
    assert out["observations"] - out["unknowns"] == out["redundancy"]
    assert line == (out["observations"], out["unknowns"], out["redundancy"])
    assert out["conditions"] == 0
    assert (summary["observations"], summary["unknowns"], summary["redundancy"]) == line
