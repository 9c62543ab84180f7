"""``orientviz solve``: reports, JSON keys in the file's units, exit codes, no tracebacks."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import orientviz as ov
from orientviz.cli import main
from orientviz.io.datasets import dataset_info, dataset_path, list_datasets
from orientviz.io.problem import Units, dumps_problem, problem_from_block


def _solve_json(capsys, *argv):
    code = main(["solve", *argv, "--json"])
    out, err = capsys.readouterr()
    return code, (json.loads(out) if out.strip() else None), err


@pytest.mark.parametrize("name", list_datasets())
def test_every_example_solves(name, capsys):
    code, out, err = _solve_json(capsys, str(dataset_path(name)))
    assert code == 0, err
    for key in ("sigma0", "converged", "iterations", "images", "points", "flagged"):
        assert key in out
    assert out["converged"] is True and out["iterations"] >= 1
    assert out["units"] == ov.load_dataset(name).units.as_dict()
    if dataset_info(name)["folder"] != "examples":
        return  # other folders' datasets: their own tests judge the numbers
    # every example here is simulated with the σ it states: σ̂0 must be near 1. With r ≥ 8
    # the 99.9 % range of σ̂0 is about [0.3, 1.8]; the similarity example's control σ
    # leaves out the model noise (0.01 mm · 5000 = 0.05 m), so its σ̂0 may reach ~1.6.
    assert 0.3 < out["sigma0"] < 1.8


def test_text_report(capsys):
    code = main(["solve", str(dataset_path("resection_example"))])
    out, err = capsys.readouterr()
    assert code == 0 and err == ""
    for words in ("sigma0 =", "redundancy 10", "converged", "omega phi kappa", "[gon]",
                  "largest normalised residuals", "flagged"):  # fmt: skip
        assert words in out


def test_dataset_name_instead_of_a_path(capsys):
    code, out, _ = _solve_json(capsys, "intersection_example")
    assert code == 0 and out["kind"] == "intersection"


def test_resection_recovers_the_simulated_orientation(capsys):
    """Noise 5 µm: the truth must lie within 4σ of the estimate (σ from the report)."""
    info = json.loads((dataset_path("resection_example").parent / "MANIFEST.json").read_text())
    truth = next(d for d in info["datasets"] if d["name"] == "resection_example")["truth"]
    code, out, _ = _solve_json(capsys, "resection_example")
    img = out["images"][0]
    for k, key in enumerate(("X0", "Y0", "Z0")):
        assert abs(img[key] - truth["X0_m"][k]) < 4 * img["sigma"][key]
    for k, key in enumerate(("omega", "phi", "kappa")):
        assert abs(img[key] - truth["omega_phi_kappa_gon"][k]) < 4 * img["sigma"][key]


def test_results_are_in_the_file_units(capsys, tmp_path):
    """The same resection in m/gon and in mm/cc reports the same numbers × 1000 / × 10⁴."""
    base = ov.load_dataset("resection_example")
    other = problem_from_block(base.data, kind="resection", units=Units("mm", "cc", "um"))
    path = tmp_path / "mm.json"
    path.write_text(dumps_problem(other), encoding="utf-8")
    _, a, _ = _solve_json(capsys, str(dataset_path("resection_example")))
    _, b, _ = _solve_json(capsys, str(path))
    ia, ib = a["images"][0], b["images"][0]
    # same adjustment up to round-off of the unit conversions (values printed to 15 digits)
    assert ib["X0"] == pytest.approx(ia["X0"] * 1000.0, rel=1e-9)
    assert ib["kappa"] == pytest.approx(ia["kappa"] * 1e4, rel=1e-9)
    assert ib["sigma"]["phi"] == pytest.approx(ia["sigma"]["phi"] * 1e4, rel=1e-5)
    assert b["sigma0"] == pytest.approx(a["sigma0"], rel=1e-5)


def test_similarity_parameters_and_units(capsys):
    code, out, _ = _solve_json(capsys, "similarity_example")
    params = {p["name"]: p for p in out["parameters"]}
    assert params["scale"]["unit"] == "" and params["kappa"]["unit"] == "gon"
    assert params["tx"]["unit"] == "m"
    truth = json.loads((dataset_path("similarity_example").parent / "MANIFEST.json").read_text())
    t = next(d for d in truth["datasets"] if d["name"] == "similarity_example")["truth"]
    assert abs(params["scale"]["value"] - t["scale"]) < 4 * params["scale"]["sigma"]
    assert abs(params["kappa"]["value"] - t["kappa_gon"]) < 4 * params["kappa"]["sigma"]
    roles = {p["id"]: p["role"] for p in out["points"]}
    assert roles["101"] == "transformed" and roles["100"] == "control"


def test_gross_error_is_flagged(capsys, tmp_path):
    doc = json.loads(dataset_path("resection_example").read_text(encoding="utf-8"))
    doc["observations"][3]["x"] += 0.060  # 60 µm = 12 σ
    path = tmp_path / "gross.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    code, out, _ = _solve_json(capsys, str(path))
    assert code == 0
    assert out["flagged"], "a 12σ error must be flagged"
    assert out["flagged"][0]["label"] == f"{doc['observations'][3]['point']}/x"
    assert abs(out["flagged"][0]["w"]) > 3.29


def test_bad_input_exit_2_one_line(capsys, tmp_path):
    path = tmp_path / "bad.json"
    path.write_text(
        '{"format": "orientviz/1", "kind": "block", "units": {"length": "furlong", "angle": "gon"}}'
    )  # ft and us-ft are lengths since issue 29
    code = main(["solve", str(path)])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err.count("\n") == 1
    assert str(path) in err and "units.length" in err and "furlong" in err


def test_missing_file_exit_2(capsys, tmp_path):
    code = main(["solve", str(tmp_path / "nope.json")])
    _, err = capsys.readouterr()
    assert code == 2 and "no such file" in err


def test_method_does_not_apply(capsys):
    code = main(["solve", str(dataset_path("similarity_example")), "--method", "bundle"])
    _, err = capsys.readouterr()
    assert code == 2 and "does not apply to a 'similarity' problem" in err


def test_datum_defect_exit_3(capsys, tmp_path):
    doc = json.loads(dataset_path("block_strip").read_text(encoding="utf-8"))
    for p in doc["points"]:
        if p["role"] == "control":
            p["role"] = "tie"
            p.pop("sigma", None)
    path = tmp_path / "free.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    code = main(["solve", str(path)])
    out, err = capsys.readouterr()
    assert code == 3 and out == ""
    assert "7 datum parameter" in err and "free: add control or fix" in err
    assert err.count("\n") == 1


def test_not_converged_exit_3_with_report(capsys, tmp_path):
    doc = json.loads(dataset_path("resection_example").read_text(encoding="utf-8"))
    doc["options"] = {"max_iter": 1}
    path = tmp_path / "one_step.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    code, out, err = _solve_json(capsys, str(path))
    assert code == 3
    assert out["converged"] is False and out["iterations"] == 1
    assert "did not converge" in err


def test_solve_problem_api_matches_cli(capsys):
    sol = ov.solve_problem(ov.load_dataset("intersection_example"))
    _, out, _ = _solve_json(capsys, "intersection_example")
    assert out["sigma0"] == pytest.approx(sol.adjustment.sigma0, rel=1e-5)
    xyz = np.array([[p["X"], p["Y"], p["Z"]] for p in out["points"]])
    np.testing.assert_allclose(xyz, sol.xyz, rtol=0, atol=1e-9)


@pytest.mark.skipif(shutil.which("orientviz") is None, reason="orientviz entry point not installed")
def test_installed_entry_point():
    """The console script runs the same code (PYTHONPATH points it at this checkout)."""
    src = str(Path(__file__).resolve().parents[2] / "src")
    env = dict(os.environ, PYTHONPATH=src + os.pathsep + os.environ.get("PYTHONPATH", ""))
    exe = shutil.which("orientviz")
    ok = subprocess.run([exe, "solve", "similarity_example", "--json"], capture_output=True,
                        text=True, env=env, timeout=120)  # fmt: skip
    assert ok.returncode == 0, ok.stderr
    assert json.loads(ok.stdout)["kind"] == "similarity" and ok.stderr == ""


def test_method_models(capsys):
    code, out, err = _solve_json(capsys, "block_strip", "--method", "models")
    assert code == 0, err
    assert out["method"].startswith("models")
    assert all(img["omega"] is None and img["X0"] is not None for img in out["images"])
    assert len(out["points"]) == 12


def test_method_polynomial_with_degrees(capsys, tmp_path):
    doc = json.loads(dataset_path("block_strip").read_text(encoding="utf-8"))
    path = tmp_path / "poly.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    # 4 height control points cannot fix 5 coefficients of a degree-2 height polynomial
    code = main(["solve", str(path), "--method", "polynomial"])
    _, err = capsys.readouterr()
    assert code == 3 and "not determinable" in err
    doc["options"].update(degree_xy=1, degree_z=1)
    path.write_text(json.dumps(doc), encoding="utf-8")
    code, out, err = _solve_json(capsys, str(path), "--method", "polynomial")
    assert code == 0, err
    assert out["method"] == "polynomial" and out["images"] == []
    assert any("check points (2)" in n for n in out["notes"])


def _strip_approximations(doc: dict) -> dict:
    for img in doc["images"]:
        for key in ("X0", "Y0", "Z0", "omega", "phi", "kappa"):
            img.pop(key, None)
    for p in doc["points"]:
        if p["role"] == "tie":
            for key in ("X", "Y", "Z"):
                p.pop(key, None)
    return doc


def test_block_without_approximations_reaches_the_same_optimum(capsys, tmp_path):
    """Images and tie points without start values: orientviz.block fills them."""
    from orientviz.simulate import simulate_block

    block = simulate_block(1, 3, rng=11, extra="grid").block
    with_start = tmp_path / "start.json"
    with_start.write_text(dumps_problem(problem_from_block(block)), encoding="utf-8")
    doc = _strip_approximations(json.loads(with_start.read_text(encoding="utf-8")))
    bare_path = tmp_path / "bare.json"
    bare_path.write_text(json.dumps(doc), encoding="utf-8")
    code, bare, err = _solve_json(capsys, str(bare_path))
    assert code == 0, err
    code, ref, err = _solve_json(capsys, str(with_start))
    assert code == 0, err
    a = np.array([[i["X0"], i["Y0"], i["Z0"]] for i in bare["images"]])
    b = np.array([[i["X0"], i["Y0"], i["Z0"]] for i in ref["images"]])
    # both stop when corrections are < 1e-3 σ (σ well below 1 m here): same optimum to < 1 mm
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-3)
    assert bare["sigma0"] == pytest.approx(ref["sigma0"], rel=1e-4)


def test_too_few_points_for_automatic_approximations(capsys, tmp_path):
    doc = _strip_approximations(json.loads(dataset_path("block_strip").read_text("utf-8")))
    path = tmp_path / "bare.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    code = main(["solve", str(path)])
    _, err = capsys.readouterr()
    assert code == 3 and "approximate values" in err and err.count("\n") == 1


def _write(tmp_path, doc, name="p.json"):
    path = tmp_path / name
    path.write_text(json.dumps(doc), encoding="utf-8")
    return str(path)


def test_resection_with_two_points_is_not_determinable(capsys, tmp_path):
    doc = json.loads(dataset_path("resection_example").read_text(encoding="utf-8"))
    keep = {doc["points"][0]["id"], doc["points"][1]["id"]}
    doc["observations"] = [o for o in doc["observations"] if o["point"] in keep]
    code = main(["solve", _write(tmp_path, doc)])
    _, err = capsys.readouterr()
    assert code == 3 and "adjustment impossible" in err and err.count("\n") == 1


def test_similarity_with_one_control_point_is_not_determinable(capsys, tmp_path):
    doc = json.loads(dataset_path("similarity_example").read_text(encoding="utf-8"))
    doc["target"]["points"] = doc["target"]["points"][:1]
    code = main(["solve", _write(tmp_path, doc)])
    _, err = capsys.readouterr()
    assert code == 3 and "7 parameters need at least 7 control coordinates" in err


def test_unknown_name_lists_the_examples(capsys):
    code = main(["solve", "blok_strip"])
    _, err = capsys.readouterr()
    assert code == 2 and "no shipped example of that name" in err and "block_strip" in err


def test_output_writes_the_adjusted_problem(capsys, tmp_path):
    out = tmp_path / "adjusted.json"
    code = main(["solve", "block_strip", "-o", str(out)])
    capsys.readouterr()
    assert code == 0
    before = ov.load_dataset("block_strip").data
    after = load_problem_file(out).data
    # the observations are unchanged; the start values are now the adjusted ones
    np.testing.assert_array_equal(after.observations.xy, before.observations.xy)
    assert not np.allclose(after.images.X0, before.images.X0, atol=1e-3)
    code, again, _ = _solve_json(capsys, str(out))
    assert code == 0
    # started at the optimum, the bundle stops after its first step with the same σ0
    _, first, _ = _solve_json(capsys, "block_strip")
    assert again["sigma0"] == pytest.approx(first["sigma0"], rel=1e-4)
    assert again["iterations"] <= 2


def test_output_refused_for_a_similarity(capsys, tmp_path):
    code = main(["solve", "similarity_example", "-o", str(tmp_path / "x.json")])
    _, err = capsys.readouterr()
    assert code == 2 and "--output writes block" in err
    assert not (tmp_path / "x.json").exists()


def load_problem_file(path):
    from orientviz.io.problem import load_problem

    return load_problem(path)
