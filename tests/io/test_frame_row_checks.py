"""The frame kinds' loaders name the first offending row (io/kinds/_checks.py)."""

from __future__ import annotations

import json

import pytest

from orientviz.errors import InputError
from orientviz.io.datasets import dataset_path
from orientviz.io.problem import loads_problem


def _doc(name: str) -> dict:
    return json.loads(dataset_path(name).read_text())


def _error(doc: dict) -> InputError:
    with pytest.raises(InputError) as exc:
        loads_problem(json.dumps(doc), "f.json")
    return exc.value


def test_intersection_point_with_one_ray_is_named():
    doc = _doc("intersection_example")
    obs = doc["observations"]
    pid = doc["points"][3]["id"]
    keep = [o for o in obs if o["point"] != pid]
    one = next(o for o in obs if o["point"] == pid)
    doc["observations"] = keep + [one]
    e = _error(doc)
    assert e.where == "points[3].id"
    assert repr(pid) in str(e) and "1 image(s)" in str(e)


def test_resection_control_point_without_z_is_named():
    doc = _doc("resection_example")
    doc["points"][2].pop("Z")
    doc["points"][5].pop("Z")
    e = _error(doc)
    assert e.where == "points[2].X"  # the first one
    assert repr(doc["points"][2]["id"]) in str(e) and "X, Y and Z" in str(e)


def test_resection_tie_point_observation_is_named():
    doc = _doc("resection_example")
    doc["points"][4]["role"] = "tie"
    pid = doc["points"][4]["id"]
    k = next(i for i, o in enumerate(doc["observations"]) if o["point"] == pid)
    e = _error(doc)
    assert e.where == f"observations[{k}].point"
    assert repr(pid) in str(e) and "tie point" in str(e)


def test_columnar_tables_name_the_column_form(tmp_path):
    from orientviz.io.problem import load_problem, save_problem

    path = tmp_path / "columnar.json"
    save_problem(load_problem(dataset_path("resection_example")), path, columnar=True)
    doc = json.loads(path.read_text())
    doc["points"]["role"][1] = "tie"
    e = _error(doc)
    assert e.where.startswith("observations.point[") and "tie point" in str(e)


@pytest.mark.parametrize("bad", [1e308, -1e20, 1.5])
def test_strip_numbers_must_be_whole_and_bounded(bad):
    """A strip number like 1e308 once escaped as OverflowError (found by test_mutations)."""
    doc = _doc("block_compact")
    doc["images"]["strip"][2] = bad
    e = _error(doc)
    assert e.where == "images.strip[2]"
    # 1.5 is refused by the schema ("integer"), huge whole floats by the loader
    assert "whole number" in str(e) or "expected integer" in str(e)


def test_strip_numbers_read_back():
    doc = _doc("block_compact")
    doc["images"]["strip"][0] = None
    doc["images"]["strip"][1] = 7.0  # a float that is a whole number is a strip number
    p = loads_problem(json.dumps(doc), "f.json")
    assert p.data.images.strip[0] == -1 and p.data.images.strip[1] == 7
