"""Problem files: round trips, units, the two table forms, the kind registry, schemas."""

from __future__ import annotations

import json

import numpy as np
import pytest

from orientviz.io.datasets import dataset_path, list_datasets, load_dataset
from orientviz.io.jsonio import load_schema, validator_for
from orientviz.io.problem import (
    FORMAT,
    Units,
    dumps_problem,
    load_problem,
    loads_problem,
    problem_from_block,
    save_problem,
    write_problem,
)
from orientviz.io.registry import available_kinds, get_kind
from orientviz.units import to_rad


def _doc(name: str) -> dict:
    return json.loads(dataset_path(name).read_text(encoding="utf-8"))


@pytest.mark.parametrize("name", list_datasets())
def test_examples_round_trip_exactly(name):
    """Every shipped file (≤ 15 significant digits) is written back byte for byte."""
    text = dataset_path(name).read_text(encoding="utf-8")
    problem = load_dataset(name)
    assert dumps_problem(problem) == text


@pytest.mark.parametrize("name", list_datasets())
def test_readable_and_columnar_forms_hold_the_same_problem(name):
    problem = load_dataset(name)
    readable = dumps_problem(problem, columnar=False)
    columnar = dumps_problem(problem, columnar=True)
    assert readable != columnar
    back = loads_problem(columnar, "columnar.json")
    assert back.columnar
    assert dumps_problem(back, columnar=False) == readable


@pytest.mark.parametrize("name", list_datasets())
def test_schemas_accept_what_the_writer_writes(name):
    problem = load_dataset(name)
    for columnar in (False, True):
        doc = json.loads(dumps_problem(problem, columnar=columnar))
        errors = list(validator_for(get_kind(problem.kind).schema).iter_errors(doc))
        assert errors == []


def test_all_schemas_are_valid_draft_2020_12():
    """Every shipped schema (the validators do not check them at run time)."""
    from importlib import resources

    from jsonschema import Draft202012Validator

    names = sorted(
        f.name for f in resources.files("orientviz.io").joinpath("schema").iterdir()
        if f.name.endswith(".json")
    )  # fmt: skip
    assert {"envelope.json", "common.json", "frame.json", "block.json"} <= set(names)
    for name in names:
        schema = load_schema(name)
        assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
        Draft202012Validator.check_schema(schema)


def test_units_are_converted_at_load():
    """The same block in m/gon/mm and in mm/cc/µm loads to the same internal numbers."""
    base = load_dataset("block_strip")
    other = problem_from_block(base.data, units=Units(length="mm", angle="cc", image="um"))
    text = dumps_problem(other)
    doc = json.loads(text)
    assert doc["units"] == {"length": "mm", "image": "um", "angle": "cc"}
    first = doc["images"][0]
    ref = _doc("block_strip")["images"][0]
    # 1 m = 1000 mm, 1 gon = 10 000 cc (written with 15 significant digits)
    assert first["X0"] == pytest.approx(ref["X0"] * 1000.0, rel=1e-14)
    assert first["omega"] == pytest.approx(ref["omega"] * 10_000.0, rel=1e-14)
    assert doc["observations"][0]["x"] == pytest.approx(
        _doc("block_strip")["observations"][0]["x"] * 1000.0, rel=1e-14
    )
    back = loads_problem(text, "mm.json").data
    b = base.data
    # two conversions (÷ and × by a power of ten or ρ) cost at most a few ulp
    np.testing.assert_allclose(back.images.X0, b.images.X0, rtol=1e-14)
    np.testing.assert_allclose(back.images.angles, b.images.angles, rtol=1e-13, atol=1e-17)
    np.testing.assert_allclose(back.observations.xy, b.observations.xy, rtol=1e-14)
    np.testing.assert_allclose(back.cameras.c, b.cameras.c, rtol=1e-14)


def test_angles_in_the_file_unit():
    p = load_dataset("intersection_example")
    omega_gon = _doc("intersection_example")["images"][0]["omega"]
    assert p.data.images.angles[0, 0] == to_rad(omega_gon, "gon")
    assert p.units == Units(length="m", angle="gon", image="mm")


def test_sequence_is_kept():
    doc = _doc("resection_example")
    doc["sequence"] = "pok"
    p = loads_problem(json.dumps(doc), "pok.json")
    assert p.sequence == "pok" and p.data.sequence == "pok"
    assert json.loads(dumps_problem(p))["sequence"] == "pok"


def test_save_is_atomic_and_leaves_no_temporary_files(tmp_path):
    p = load_dataset("similarity_example")
    target = tmp_path / "out.json"
    save_problem(p, target)
    assert load_problem(target).kind == "similarity"
    assert sorted(x.name for x in tmp_path.iterdir()) == ["out.json"]


def test_failed_write_keeps_the_old_file(tmp_path, monkeypatch):
    import orientviz.io.jsonio as jsonio

    target = tmp_path / "out.json"
    target.write_text("old", encoding="utf-8")
    p = load_dataset("block_strip")
    p.data.observations.xy[0, 0] = np.nan  # a NaN cannot be written as JSON
    with pytest.raises(ValueError):
        save_problem(p, target)
    assert target.read_text(encoding="utf-8") == "old"
    assert sorted(x.name for x in tmp_path.iterdir()) == ["out.json"]
    assert jsonio  # module used by save_problem


def test_write_problem_accepts_an_importer_dict(tmp_path):
    b = load_dataset("block_compact").data
    out = write_problem({"kind": "block", "block": b}, tmp_path / "b.json")
    again = load_problem(out)
    assert again.kind == "block" and again.data.summary() == b.summary()
    np.testing.assert_array_equal(again.data.observations.image, b.observations.image)


def test_registry_lists_and_imports_kinds_lazily():
    kinds = available_kinds()
    assert {"block", "resection", "intersection", "similarity"} <= set(kinds)
    k = get_kind("similarity")
    assert k.schema == "similarity.json" and k.solve is not None


def test_missing_tie_coordinates_are_allowed_in_a_block():
    doc = _doc("block_strip")
    for row in doc["points"]:
        if row["role"] == "tie":
            for key in ("X", "Y", "Z"):
                row.pop(key)
    p = loads_problem(json.dumps(doc), "no_ties.json")
    tie = p.data.points.role == 0
    assert np.all(np.isnan(p.data.points.xyz[tie]))
    assert p.data.points.xyz[~tie].size and np.all(np.isfinite(p.data.points.xyz[~tie]))


def test_format_constant():
    assert _doc("block_strip")["format"] == FORMAT == "orientviz/1"


def test_package_level_exports():
    import orientviz.io as io

    assert io.load_problem is load_problem and io.list_datasets is list_datasets
    assert set(io.__all__) >= {"load_problem", "save_problem", "load_dataset", "solve_problem"}
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        io.nothing  # noqa: B018


def test_writing_into_a_missing_folder_is_an_input_error(tmp_path):
    from orientviz.errors import InputError

    p = load_dataset("similarity_example")
    with pytest.raises(InputError, match="cannot write") as info:
        save_problem(p, tmp_path / "no" / "such" / "out.json")
    assert str(tmp_path / "no" / "such" / "out.json") in str(info.value)
    with pytest.raises(InputError, match="is a directory"):
        save_problem(p, tmp_path)


def test_height_only_control_point():
    """A control point with X, Y null is a height point: X, Y not given, Z fixed (σ 0)."""
    doc = _doc("block_compact")
    i = doc["points"]["role"].index("control")
    doc["points"]["X"][i] = doc["points"]["Y"][i] = None
    p = loads_problem(json.dumps(doc), "height.json")
    pts = p.data.points
    assert np.all(np.isnan(pts.xyz_known[i, :2])) and np.isfinite(pts.xyz_known[i, 2])
    assert np.all(np.isnan(pts.sigma[i, :2])) and pts.sigma[i, 2] == 0.0
    again = json.loads(dumps_problem(p))
    assert again["points"]["X"][i] is None and again["points"]["Z"][i] == doc["points"]["Z"][i]


@pytest.mark.parametrize("angle", ["rad", "deg", "gon", "c", "cc"])
@pytest.mark.parametrize("length,image", [("m", "mm"), ("mm", "um")])
def test_every_unit_round_trips(angle, length, image):
    b = load_dataset("block_strip").data
    p = problem_from_block(b, units=Units(length=length, angle=angle, image=image))
    back = loads_problem(dumps_problem(p), "u.json").data
    # one multiplication and one division by the unit factor, 15 written digits: ≤ 1e-14
    np.testing.assert_allclose(back.images.angles, b.images.angles, rtol=1e-14, atol=1e-18)
    np.testing.assert_allclose(back.images.X0, b.images.X0, rtol=1e-14)
    np.testing.assert_allclose(back.observations.sigma, b.observations.sigma, rtol=1e-14)
    np.testing.assert_array_equal(back.points.role, b.points.role)
