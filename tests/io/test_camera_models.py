"""cameras[] camera models and image units in pixels in problem files (issue #20 point 1)."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

from orientviz.bundle import Ebner12, bundle_adjust
from orientviz.io.problem import (
    dumps_problem,
    loads_problem,
    problem_from_block,
    problem_from_document,
)
from orientviz.io.solve import solve_problem
from orientviz.reproduce import dbat_camcal as D
from orientviz.simulate import simulate_block


@pytest.fixture(scope="module")
def camcal_doc():
    return D.problem_document()


def test_dbat_calibration_from_a_pixel_problem_file_equals_the_bundle_route(camcal_doc):
    sol = solve_problem(problem_from_document(copy.deepcopy(camcal_doc)))
    res = D.adjust()[0]
    assert f"{sol.adjustment.sigma0:.4f}" == "1.6148" == D.paper_values()["summary||sigma0"]
    assert abs(sol.adjustment.sigma0 - res.sigma0) < 1e-9
    p = camcal_doc["units"]["pixel_size"]
    cam = sol.adjustment.camera
    # c and the principal point came in as pixels (y down): the same mm camera results
    assert abs(cam.get("c")[0] - res.camera.get("c")[0]) < 1e-9
    assert abs(cam.get("y0")[0] - res.camera.get("y0")[0]) < 1e-9
    assert abs(cam.get("y0")[0] + camcal_doc["cameras"][0]["y0"] * p) > 0.01  # it moved
    line = next(n for n in sol.notes if n.startswith("camera C4040Z"))
    c_px = float(line.split("c ")[1].split(" ±")[0])
    assert abs(c_px * p - cam.get("c")[0]) < 1e-6
    assert any("K2~K3" in n for n in sol.notes)  # the high correlation is reported
    params = {q["name"]: q for q in sol.as_dict()["parameters"]}  # --json: full precision
    assert params["C4040Z.c"]["unit"] == "px"
    assert abs(params["C4040Z.c"]["value"] * p - cam.get("c")[0]) < 1e-9
    assert abs(-params["C4040Z.y0"]["value"] * p - cam.get("y0")[0]) < 1e-9  # y down
    assert params["C4040Z.K1 [mm⁻²]"]["value"] == pytest.approx(cam.get("K1")[0], rel=1e-12)
    assert "C4040Z.sk" not in params  # fixed: not an estimate


def _to_pixels(doc: dict, p: float) -> dict:
    """The same block with image coordinates in pixels (y down) — written by hand."""
    d = copy.deepcopy(doc)
    d["units"].update(image="px", pixel_size=p)
    for cam in d["cameras"]:
        cam["c"] /= p
        cam["x0"] = cam.get("x0", 0.0) / p
        cam["y0"] = -cam.get("y0", 0.0) / p
        cam["format"] = [f / p for f in cam["format"]]
    for o in d["observations"]:
        o["x"], o["y"] = o["x"] / p, -o["y"] / p
        o["sigma"] = (
            o["sigma"] / p if not isinstance(o["sigma"], list) else [s / p for s in o["sigma"]]
        )
    return d


def test_pixels_with_y_down_give_the_same_adjustment_as_millimetres():
    block = simulate_block(1, 5, rng=3, control="full").block
    doc = json.loads(dumps_problem(problem_from_block(block, columnar=False)))
    assert doc["units"]["image"] == "mm"
    mm = solve_problem(problem_from_document(copy.deepcopy(doc)))
    px = solve_problem(problem_from_document(_to_pixels(doc, 0.012)))
    assert abs(mm.adjustment.sigma0 - px.adjustment.sigma0) < 1e-9 * mm.adjustment.sigma0
    assert np.allclose(mm.X0, px.X0, atol=1e-9)
    # a mirrored y (pixels read as y up) does not fit: the flip is what makes it work
    bad = _to_pixels(doc, 0.012)
    for o in bad["observations"]:
        o["y"] = -o["y"]
    assert solve_problem(problem_from_document(bad)).adjustment.sigma0 > 10 * mm.adjustment.sigma0


def test_camera_models_survive_a_write_and_read(camcal_doc):
    doc = copy.deepcopy(camcal_doc)
    doc["cameras"][0].update(K1=1e-3, sigma={"sk": 1e-4, "y0": 2.0})
    doc["cameras"][0]["free"].remove("K1")
    doc["cameras"][0]["free"].remove("y0")
    prob = problem_from_document(doc)
    again = loads_problem(dumps_problem(prob))
    a, b = prob.data, again.data
    assert a.cameras.model == b.cameras.model
    assert b.cameras.model[0]["sigma"]["y0"] == pytest.approx(2.0 * doc["units"]["pixel_size"])
    assert np.allclose(a.observations.xy, b.observations.xy, atol=1e-12)
    assert np.allclose(a.cameras.y0, b.cameras.y0, atol=1e-12)


def test_an_additional_parameter_set_per_camera_from_the_file():
    block = simulate_block(2, 6, rng=5, control="full").block
    doc = json.loads(dumps_problem(problem_from_block(block, columnar=False)))
    doc["cameras"][0].update(additional="ebner12", additional_sigma=10.0)
    sol = solve_problem(problem_from_document(doc))
    b = 0.4 * float(np.min(block.cameras.format_mm[0]))
    ref = bundle_adjust(block, additional=Ebner12(b=b), ap_sigma=10.0)
    assert abs(sol.adjustment.sigma0 - ref.sigma0) < 1e-9 * ref.sigma0
    assert sol.adjustment.additional.size == 12


def test_a_calibration_without_its_lens_terms_does_not_fit_and_says_so(
    camcal_doc, tmp_path, capsys
):
    from orientviz.cli import main

    doc = copy.deepcopy(camcal_doc)
    for k in ("model", "free"):
        del doc["cameras"][0][k]
    path = tmp_path / "nolens.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    code = main(["solve", str(path), "-o", str(tmp_path / "out.json")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 4  # not 0: the estimates of a model that does not fit are no result
    assert len(err) == 1 and "the model does not fit the data" in err[0]
    # a file in pixels: the causes named are the lens and c, not a pixel size (c is in px too)
    assert "lens distortion" in err[0] and "principal distance" in err[0] and str(path) in err[0]
    assert "pixel size" not in err[0]
    assert not (tmp_path / "out.json").exists()
    assert main(["solve", "dbat_camcal"]) == 0  # with its model the same data fit


def test_the_shipped_calibration_file_is_what_the_converter_writes_now():
    from orientviz.io.datasets import dataset_path

    assert dataset_path("dbat_camcal").read_text(encoding="utf-8") == D.problem_text()


def test_parameters_of_an_additional_set_free_weighted_or_fixed():
    block = simulate_block(2, 6, rng=5, control="full").block
    doc = json.loads(dumps_problem(problem_from_block(block, columnar=False)))
    doc["cameras"][0].update(additional="ebner12", free=["b1", "b2"], sigma={"b3": 5.0})
    sol = solve_problem(problem_from_document(doc))
    b = 0.4 * float(np.min(block.cameras.format_mm[0]))
    sig = np.full(12, 1e-6)  # the others held at 0
    sig[:2], sig[2] = np.inf, 5.0
    ref = bundle_adjust(block, additional=Ebner12(b=b), ap_sigma=sig)
    assert abs(sol.adjustment.sigma0 - ref.sigma0) < 1e-9 * ref.sigma0
    a = sol.adjustment.additional
    assert np.all(np.abs(a[3:]) < 1e-9) and np.any(np.abs(a[:3]) > 1e-3)
    doc["cameras"][0]["free"] = ["k1"]
    with pytest.raises(Exception, match=r"cameras\[0\]\.free: 'k1' is not a parameter of ebner12"):
        problem_from_document(doc)
