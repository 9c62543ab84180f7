"""The textbook reference on the shipped DBAT block (sxb: 5 aerial images, weighted
control, check points with their rays) agrees with ``orientviz solve dbat_sxb``."""

from __future__ import annotations

import json

import numpy as np
import pytest
from test_reference import one_blas_thread  # noqa: F401

import orientviz as ov
from orientviz.bundle.reference import reference_bundle
from orientviz.cli import main
from orientviz.io.datasets import load_dataset
from orientviz.io.kinds.block import prepare, with_check_rays


def _solve(capsys, *argv: str) -> dict:
    assert main(["solve", "dbat_sxb", "--json", *argv]) == 0
    return json.loads(capsys.readouterr().out)


def test_solve_dbat_sxb_with_the_reference_gives_the_same_sigma0_and_stations(capsys):
    fast = _solve(capsys)
    ref = _solve(capsys, "--solver", "reference")
    assert fast["converged"] and ref["converged"]
    assert (ref["iterations"], ref["redundancy"]) == (fast["iterations"], fast["redundancy"])
    assert ref["sigma0"] == pytest.approx(fast["sigma0"], rel=1e-10)
    H = np.mean([i["Z0"] for i in fast["images"]]) - np.mean([p["Z"] for p in fast["points"]])
    for a, b in zip(fast["images"], ref["images"]):
        assert a["id"] == b["id"]
        dX = max(abs(a[k] - b[k]) for k in ("X0", "Y0", "Z0"))
        dang = max(abs(a[k] - b[k]) for k in ("omega", "phi", "kappa"))  # deg (the file's)
        assert dX / H < 1e-10 and np.radians(dang) < 1e-10, (a["id"], dX, dang)
        for k, s in a["sigma"].items():
            assert b["sigma"][k] == pytest.approx(s, rel=1e-8), (a["id"], k)


def test_reference_and_fast_bundle_meet_far_below_the_default_tolerance():
    problem = load_dataset("dbat_sxb")
    # coordinates of 1e6 m: the stopping measure's rounding floor is ~1e-8 conditional σ
    problem.options["tol"] = 2e-8
    fast = ov.solve_problem(problem)
    problem.options["solver"] = "reference"
    ref = ov.solve_problem(problem)
    assert ref.adjustment.solver == "reference" and fast.adjustment.solver == "dense"
    assert ref.adjustment.converged and fast.adjustment.converged
    assert ref.adjustment.sigma0 == pytest.approx(fast.adjustment.sigma0, rel=1e-12)
    H = float(np.mean(fast.X0[:, 2]) - np.mean(fast.xyz[:, 2]))
    assert np.max(np.abs(ref.X0 - fast.X0)) / H < 1e-12
    assert np.max(np.abs(ref.angles - fast.angles)) < 1e-12
    assert np.max(np.abs(ref.xyz - fast.xyz)) / H < 1e-12


def test_the_reference_functions_on_the_block_that_solve_adjusts():
    # what a lesson does: the block `orientviz solve dbat_sxb` adjusts (approximations,
    # check points kept as tie points: options.check_points = "rays"), then the reference
    # module's own loop, without the result adapter
    problem = load_dataset("dbat_sxb")
    block = with_check_rays(prepare(problem)[0])
    ref = reference_bundle(block, control="weighted", tol=2e-8, max_iter=20)
    problem.options["tol"] = 2e-8
    fast = ov.solve_problem(problem)
    assert ref.converged and fast.adjustment.converged
    s0 = np.sqrt(ref.cost[-1] / fast.adjustment.redundancy)
    assert s0 == pytest.approx(fast.adjustment.sigma0, rel=1e-12)
    H = float(np.mean(fast.X0[:, 2]) - np.mean(fast.xyz[:, 2]))
    assert np.max(np.abs(ref.X0 - fast.X0)) / H < 1e-12
    assert np.max(np.abs(ref.angles - fast.angles)) < 1e-12
