"""`orientviz export` of a block whose cameras are refined writes the refined cameras."""

from __future__ import annotations

import numpy as np

from orientviz.cli import main
from orientviz.io.datasets import load_dataset
from orientviz.io.problem import load_problem
from orientviz.io.solve import solve_problem


def test_exported_problem_carries_the_refined_camera(tmp_path):
    problem = load_dataset("dbat_camcal")  # its camera model estimates c, x0, y0 and terms
    cam = solve_problem(problem).adjustment.camera
    assert main(["export", "dbat_camcal", "-d", str(tmp_path), "--format", "json"]) == 0
    out = load_problem(tmp_path / "adjusted.json").data.cameras
    start = problem.data.cameras
    for j, name in enumerate(cam.names):
        if name in ("c", "x0", "y0") and cam.estimated[j]:
            got, was = getattr(out, name)[0], getattr(start, name)[0]
            # export's own bundle run: the solve's optimum to its stopping tolerance
            assert abs(got - cam.value[0, j]) < 1e-3 * abs(was - cam.value[0, j]), name
    terms = out.model[0].get("values", {}) if out.model and out.model[0] else {}
    estimated_terms = [
        n for j, n in enumerate(cam.names) if cam.estimated[j] and n not in ("c", "x0", "y0")
    ]
    for name in estimated_terms:
        assert np.isclose(terms[name], cam.value[0, cam.names.index(name)], rtol=1e-6), name
