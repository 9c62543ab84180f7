"""Bad problem files: one InputError per defect, naming the file, the place and the problem."""

from __future__ import annotations

import copy
import json

import pytest

import orientviz as ov
from orientviz.errors import DatumDefectError
from orientviz.io.datasets import dataset_path
from orientviz.io.problem import loads_problem

SOURCE = "bad.json"


def _doc(name: str = "block_strip") -> dict:
    return json.loads(dataset_path(name).read_text(encoding="utf-8"))


def _fail(doc_or_text, match: str) -> ov.InputError:
    text = doc_or_text if isinstance(doc_or_text, str) else json.dumps(doc_or_text)
    with pytest.raises(ov.InputError, match=match) as info:
        loads_problem(text, SOURCE)
    err = info.value
    line = str(err)
    assert "\n" not in line
    assert line.startswith(f"{SOURCE}: ")
    return err


def test_malformed_json_names_line_and_column():
    text = dataset_path("block_strip").read_text(encoding="utf-8")
    lines = text.splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith('  {"id": "s00_000"'))
    lines[k] = lines[k].rstrip(",")  # drop the comma between the first two images
    err = _fail("\n".join(lines), "malformed JSON: Expecting ',' delimiter")
    assert err.where == f"line {k + 2}, column 3"  # 1-based: the line after the row


def test_truncated_file():
    text = dataset_path("block_strip").read_text(encoding="utf-8")
    err = _fail(text[: len(text) // 2], "malformed JSON")
    assert err.where.startswith("line ")


def test_not_an_object():
    _fail("[1, 2, 3]", r"expected a JSON object .* got an array")


def test_missing_format():
    doc = _doc()
    del doc["format"]
    _fail(doc, "missing field 'format'")


def test_unknown_format():
    doc = _doc()
    doc["format"] = "orientviz/2"
    err = _fail(doc, "unsupported format 'orientviz/2'")
    assert err.where == "format"


def test_unknown_kind_lists_the_known_ones():
    doc = _doc()
    doc["kind"] = "teleport"
    err = _fail(doc, r"unknown kind 'teleport' \(known: .*block.*similarity")
    assert err.where == "kind"


def test_missing_field_in_a_row():
    doc = _doc()
    del doc["observations"][12]["x"]
    err = _fail(doc, "missing field 'x'")
    assert err.where == "observations[12]"


def test_missing_table():
    doc = _doc()
    del doc["observations"]
    _fail(doc, "missing field 'observations'")


def test_extra_top_level_field():
    doc = _doc()
    doc["colour"] = "blue"
    err = _fail(doc, "unexpected field 'colour'")
    assert err.where == "colour"


def test_extra_field_in_a_row():
    doc = _doc()
    doc["points"][2]["colour"] = "red"
    err = _fail(doc, "unexpected field 'colour'")
    assert err.where == "points[2].colour"


def test_wrong_type():
    doc = _doc()
    doc["observations"][3]["x"] = "12.5"
    err = _fail(doc, "expected number, got a string")
    assert err.where == "observations[3].x"


def test_wrong_shape_of_a_vector():
    doc = _doc()
    doc["cameras"][0]["format"] = [230.0]
    err = _fail(doc, "expected at least 2 item")
    assert err.where == "cameras[0].format"


def test_columns_of_different_length():
    doc = _doc("block_compact")
    doc["observations"]["y"].pop()
    err = _fail(doc, "column has .* entries but column 'image' has")
    assert err.where == "observations.y"


def test_columnar_place_is_named_in_columnar_form():
    doc = _doc("block_compact")
    doc["observations"]["point"][7] = "nowhere"
    err = _fail(doc, "unknown point id 'nowhere'")
    assert err.where == "observations.point[7]"


@pytest.mark.parametrize(
    "token", ["NaN", "Infinity", "-Infinity", "1e999", "1" + "0" * 400, "9" * 5000]
)
def test_non_finite_numbers_are_rejected(token):
    text = json.dumps(_doc())
    marker = '"x": '
    pos = text.index(marker, text.index('"observations"'))
    end = text.index(",", pos)
    bad = text[: pos + len(marker)] + token + text[end:]
    err = _fail(bad, "not a finite number")
    assert err.where == "observations[0].x"


def test_nan_string_is_a_type_error():
    doc = _doc()
    doc["images"][1]["omega"] = "NaN"
    err = _fail(doc, "expected number or null, got a string")
    assert err.where == "images[1].omega"


def test_duplicate_key():
    text = json.dumps(_doc())
    text = text.replace('"kind": "block"', '"kind": "block", "kind": "block"', 1)
    err = _fail(text, "duplicate key 'kind'")
    assert err.where == "document"


def test_unknown_image_id():
    doc = _doc()
    doc["observations"][4]["image"] = "zzz"
    err = _fail(doc, "unknown image id 'zzz'")
    assert err.where == "observations[4].image"


def test_unknown_camera_id():
    doc = _doc()
    doc["images"][0]["camera"] = "leica"
    err = _fail(doc, "unknown camera id 'leica'")
    assert err.where == "images[0].camera"


def test_duplicate_point_id():
    doc = _doc()
    doc["points"][5]["id"] = doc["points"][1]["id"]
    err = _fail(doc, r"duplicate point id .* \(first at points\[1\]\.id\)")
    assert err.where == "points[5].id"


def test_duplicate_observation():
    doc = _doc()
    doc["observations"].append(copy.deepcopy(doc["observations"][0]))
    _fail(doc, "observed twice in image")


def test_tie_point_with_one_ray():
    doc = _doc()
    tie = next(p["id"] for p in doc["points"] if p["role"] == "tie")
    rows = [k for k, o in enumerate(doc["observations"]) if o["point"] == tie]
    doc["observations"] = [o for k, o in enumerate(doc["observations"]) if k not in rows[1:]]
    err = _fail(doc, f"tie point '{tie}' is observed in 1 image.*at least 2 ray")
    assert err.where.startswith("points[") and err.where.endswith("].id")


def test_unknown_unit():
    doc = _doc()
    doc["units"]["length"] = "furlong"  # ft and us-ft are lengths since issue 29
    err = _fail(doc, 'expected one of "m", "mm", "ft", "us-ft", "model", got "furlong"')
    assert err.where == "units.length"


def test_missing_image_unit_in_a_frame_kind():
    doc = _doc()
    del doc["units"]["image"]
    err = _fail(doc, "missing field 'image'")
    assert err.where == "units"


def test_unknown_sequence():
    doc = _doc()
    doc["sequence"] = "kpo"
    err = _fail(doc, "expected one of")
    assert err.where == "sequence"


def test_negative_sigma():
    doc = _doc()
    doc["observations"][2]["sigma"] = -0.005
    err = _fail(doc, "expected a number ≥ 0")
    assert err.where == "observations[2].sigma"


def test_zero_image_sigma():
    doc = _doc()
    doc["observations"][2]["sigma"] = 0
    err = _fail(doc, "σ > 0")
    assert err.where == "observations[2].sigma"


def test_missing_sigma_without_default():
    doc = _doc()
    del doc["observations"][6]["sigma"]
    err = _fail(doc, "give sigma per observation or options.image_sigma")
    assert err.where == "observations[6].sigma"
    doc["options"]["image_sigma"] = 0.004
    assert loads_problem(json.dumps(doc), SOURCE).data.observations.sigma[6, 0] == 0.004


def test_empty_table():
    doc = _doc()
    doc["images"] = []
    err = _fail(doc, "expected at least 1 item")
    assert err.where == "images"


def test_resection_needs_exactly_one_image():
    doc = _doc("resection_example")
    doc["images"].append(dict(doc["images"][0], id="img2"))
    err = _fail(doc, "exactly one image, got 2")
    assert err.where == "images"


def test_resection_approximations_all_or_none():
    doc = _doc("resection_example")
    doc["images"][0]["X0"] = 2500.0
    err = _fail(doc, "all six approximate values or none")
    assert err.where == "images[0].Y0"


def test_intersection_needs_known_orientations():
    doc = _doc("intersection_example")
    del doc["images"][1]["kappa"]
    err = _fail(doc, "the known orientation is required")
    assert err.where == "images[1].kappa"


def test_block_approximate_orientations_all_or_none():
    doc = _doc()
    doc["images"][2]["Z0"] = None
    err = _fail(doc, r"an approximate value \(give all images' or none\) is required")
    assert err.where == "images[2].Z0"


def test_similarity_target_without_source():
    doc = _doc("similarity_example")
    doc["target"]["points"][0]["id"] = "999"
    err = _fail(doc, "unknown point id '999'")
    assert err.where == "target.points[0].id"


def test_similarity_zero_sigma_is_named():
    doc = _doc("similarity_example")
    doc["target"]["points"][1]["sigma"] = 0
    err = _fail(doc, "σ > 0")
    assert err.where == "target.points[1].sigma"


def test_file_errors(tmp_path):
    with pytest.raises(ov.InputError, match="no such file") as info:
        ov.load_problem(tmp_path / "missing.json")
    assert str(tmp_path / "missing.json") in str(info.value)
    with pytest.raises(ov.InputError, match="is a directory"):
        ov.load_problem(tmp_path)
    binary = tmp_path / "image.json"
    binary.write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe")
    with pytest.raises(ov.InputError, match="not UTF-8"):
        ov.load_problem(binary)


def test_datum_defect_when_the_block_has_no_control():
    doc = _doc()
    for p in doc["points"]:
        if p["role"] == "control":
            p["role"] = "tie"
            p.pop("sigma", None)
    problem = loads_problem(json.dumps(doc), SOURCE)
    with pytest.raises(DatumDefectError, match="7 datum parameter.* free: add control or fix"):
        ov.solve_problem(problem)


def _nested(depth: int) -> str:
    text = json.dumps(dict(_doc(), description="@@"))
    return text.replace('"@@"', "[" * depth + "]" * depth)


def test_nested_value_of_the_wrong_type():
    err = _fail(_nested(50), "expected string, got an array")
    assert err.where == "description"


def test_absurdly_deep_nesting_is_one_line_not_a_recursion_error():
    _fail(_nested(100_000), "nested too deeply")
