"""parse_json: numbers parsed in C first give the document of the strict parse."""

from __future__ import annotations

import json
import math

import pytest

from orientviz.errors import InputError
from orientviz.io import jsonio
from orientviz.io.jsonio import MAX_TEXT_LENGTH, parse_json


def _strict(text: str):
    return json.loads(
        text,
        parse_constant=jsonio._NonFinite,
        parse_float=jsonio._parse_float,
        parse_int=jsonio._parse_int,
        object_pairs_hook=jsonio._pairs_hook,
    )


def test_clean_document_equals_the_strict_parse():
    text = json.dumps(
        {"a": [1.5, -0.0, 1e308, -1e-320, 10**300, "x", None, True, [2, 3.25]], "b": {"c": 7}}
    )
    doc = parse_json(text, "t.json")
    assert doc == _strict(text)
    assert math.copysign(1.0, doc["a"][1]) == -1.0
    assert type(doc["a"][4]) is int and type(doc["b"]["c"]) is int


@pytest.mark.parametrize(
    "value",
    [
        math.inf,
        -math.inf,
        math.nan,
        10**400,
        "é",
        "x" * (MAX_TEXT_LENGTH + 1),
        jsonio._NonFinite("NaN"),
    ],
)
def test_suspect_finds_each_kind_nested(value):
    assert not jsonio._suspect({"a": [0, 1.0, "id", None, {"b": [2.5]}]})
    assert jsonio._suspect({"a": [0, {"b": [2.5, value]}]})
    assert jsonio._suspect({"a": value})


def test_suspect_finds_keys_and_duplicates():
    assert jsonio._suspect({"é": 1})
    assert jsonio._suspect({"a": [_strict('{"k": 1, "k": 2}')]})


def test_late_overflow_is_reported_with_its_token_and_path():
    text = '{"x": [' + ", ".join(["1.25"] * 500) + ', 1e999], "y": 2}'
    with pytest.raises(InputError, match="1e999 is not a finite number") as info:
        parse_json(text, "t.json")
    assert info.value.where == "x[500]"


@pytest.mark.parametrize("rows", [250_000, 400_000])
def test_a_file_of_dense_structure_is_refused_with_its_count(tmp_path, rows):
    from orientviz.io.jsonio import read_json_file

    text = '{"a": [' + ",".join(["[{}]"] * rows) + "]}"
    path = tmp_path / "dense.json"
    path.write_text(text, encoding="utf-8")
    n = text.count("{") + text.count("[")
    with pytest.raises(InputError, match=f"^.*{n} JSON objects/arrays in {len(text)} bytes"):
        read_json_file(path)


def test_a_large_file_of_numbers_passes_the_structure_check(tmp_path):
    from orientviz.io.jsonio import read_json_file

    values = [0.125 * k for k in range(200_000)]
    path = tmp_path / "numbers.json"
    path.write_text(json.dumps({"x": values}), encoding="utf-8")
    assert path.stat().st_size > 2**20
    assert read_json_file(path) == {"x": values}
