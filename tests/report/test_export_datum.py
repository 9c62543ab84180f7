"""`orientviz export` of a model without control: the datum options of `solve`
(``--free``, ``--fix``), its messages, and the same adjustment as `solve`."""

from __future__ import annotations

import json

import numpy as np
import pytest

from orientviz.cli import main
from orientviz.io.colmap import write_colmap
from orientviz.io.problem import load_problem
from orientviz.simulate import simulate_block


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    """A COLMAP model imported without control (no datum of its own, model units, deg)."""
    folder = tmp_path_factory.mktemp("export_datum")
    block = simulate_block(1, 5, rng=7, control="full").block
    write_colmap(block, folder / "sparse", pixel_size_mm=0.01)
    out = folder / "m.json"
    assert main(["import-colmap", str(folder / "sparse"), "-o", str(out)]) == 0
    return out


def _images(path):
    b = load_problem(path).data
    return list(b.images.ids), b.images.X0, b.images.angles


def test_without_a_datum_it_names_free_and_fix_and_writes_nothing(model, tmp_path, capsys):
    capsys.readouterr()
    target = tmp_path / "r"
    assert main(["export", str(model), "-d", str(target)]) == 3
    err = capsys.readouterr().err
    assert f"(orientviz export {model} -d {target} --free)" in err
    assert "--fix IMAGE --fix IMAGE2:X0" in err
    assert not target.exists() or not any(target.iterdir())


def test_free_exports_what_solve_free_writes(model, tmp_path, capsys):
    assert main(["export", str(model), "-d", str(tmp_path / "r"), "--free"]) == 0
    out = capsys.readouterr().out
    assert "datum by minimum constraints" in out  # the datum its σ refer to
    assert main(["solve", str(model), "--free", "-o", str(tmp_path / "s.json"), "--json"]) == 0
    solved = json.loads(capsys.readouterr().out)
    ids, X0, ang = _images(tmp_path / "r" / "adjusted.json")
    ids_s, X0_s, ang_s = _images(tmp_path / "s.json")
    assert ids == ids_s
    np.testing.assert_array_equal(X0, X0_s)  # the same adjustment, not just a nearby one
    np.testing.assert_array_equal(ang, ang_s)
    start = load_problem(model).data.images.X0
    assert np.abs(X0 - start).max() > 1e-6  # and it did adjust
    # the CSV: the file's angle unit (deg, not gon) and the solve's σ
    lines = (tmp_path / "r" / "images.csv").read_text().splitlines()
    head = lines[0].split(",")
    assert "omega[deg]" in head and not any("[gon]" in h for h in head)
    rows = {r.split(",")[0]: r.split(",") for r in lines[1:]}
    for img in solved["images"]:
        s = img["sigma"]["Z0"]
        got = float(rows[img["id"]][head.index("sZ0[model]")])
        assert (s is None and not got > 0) or got == pytest.approx(s, rel=1e-5)


def test_fix_holds_the_named_images(model, tmp_path, capsys):
    ids, X0, ang = _images(model)
    argv = ["export", str(model), "-d", str(tmp_path / "r"), "--fix", ids[0]]
    assert main([*argv, "--fix", f"{ids[-1]}:X0"]) == 0
    assert f"datum: {ids[0]}, {ids[-1]}:X0 held at the given values" in capsys.readouterr().out
    ids_e, X0_e, ang_e = _images(tmp_path / "r" / "adjusted.json")
    np.testing.assert_allclose(X0_e[0], X0[0], rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(ang_e[0], ang[0], rtol=1e-13, atol=1e-15)
    assert X0_e[-1][0] == pytest.approx(X0[-1][0], rel=1e-13)
    assert np.abs(X0_e[1:-1] - X0[1:-1]).max() > 1e-6


def test_a_bad_fix_reads_as_in_solve(model, tmp_path, capsys):
    capsys.readouterr()
    assert main(["export", str(model), "-d", str(tmp_path / "r"), "--fix", "nope"]) == 2
    exported = capsys.readouterr().err.strip()
    assert main(["solve", str(model), "--fix", "nope"]) == 2
    solved = capsys.readouterr().err.strip()
    assert "nope" in solved
    assert exported.removeprefix("orientviz export") == solved.removeprefix("orientviz solve")
