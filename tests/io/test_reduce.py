"""The array reduction before schema validation gives the same verdict as full validation."""

from __future__ import annotations

import json
from functools import cache

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from orientviz.errors import InputError
from orientviz.io.jsonio import format_path, load_schema, validate, validator_for
from orientviz.io.problem import dumps_problem, problem_from_block
from orientviz.io.reduce import MIN_LENGTH, reduce_document


@cache
def _big_docs() -> dict[str, dict]:
    from orientviz.simulate import simulate_block

    block = simulate_block(2, 6, rng=7, extra=None, n_check=2).block
    assert block.n_observations > MIN_LENGTH
    p = problem_from_block(block)
    return {
        form: json.loads(dumps_problem(p, columnar=form == "columnar"))
        for form in ("readable", "columnar")
    }


def _cells(node, path=()):
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _cells(v, path + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _cells(v, path + (i,))
    else:
        yield path


def test_long_arrays_are_reduced_and_short_ones_kept():
    doc = _big_docs()["columnar"]
    reduced, maps = reduce_document(doc)
    n = len(doc["observations"]["x"])
    assert n > MIN_LENGTH
    assert len(reduced["observations"]["x"]) < n
    assert reduced["cameras"] == doc["cameras"]
    assert maps  # the index maps of the reduced arrays
    assert list(validator_for("block.json").iter_errors(reduced)) == []


BAD_VALUES = [None, "s", "", -1.0, 0, 0.0, 1.5, True, [], {}, [1.0, 2.0], "tie", "x" * 3]


# 150 examples passed when this was written (~40 s); 16 keep the suite fast
@settings(max_examples=16, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(form=st.sampled_from(["readable", "columnar"]), data=st.data())
def test_same_verdict_as_full_validation(form, data):
    doc = json.loads(json.dumps(_big_docs()[form]))
    cells = [c for c in _cells(doc) if c and c[0] in ("images", "points", "observations")]
    path = data.draw(st.sampled_from(cells))
    node = doc
    for part in path[:-1]:
        node = node[part]
    node[path[-1]] = data.draw(st.sampled_from(BAD_VALUES))
    full = list(validator_for("block.json").iter_errors(doc))
    try:
        validate(doc, "block.json", "big.json")
    except InputError as exc:
        assert full, "the reduction reported an error the full validation does not see"
        full_paths = {format_path(e.absolute_path) for e in full}
        # the reported place is one the full validation also flags (or inside it)
        assert any(exc.where == p or exc.where.startswith(p + ".") for p in full_paths), (
            exc.where,
            full_paths,
        )
    else:
        assert not full, f"missed: {[format_path(e.absolute_path) for e in full]}"


def test_shipped_schemas_follow_the_reduction_rules():
    """No keyword on long arrays that the reduction cannot honour (see reduce.py)."""
    forbidden = {"maxItems", "contains", "prefixItems", "dependentRequired"}
    scalar = {"string", "number", "integer", "boolean", "null"}

    def walk(node, where):
        if isinstance(node, dict):
            if node.get("type") == "array" and "items" in node and "maxItems" not in node:
                # a table or column: may be long
                assert not (forbidden & set(node)), (where, forbidden & set(node))
                if node.get("uniqueItems"):  # kept exact for arrays of scalars only
                    items = node["items"]
                    assert "enum" in items or items.get("type") in scalar, where
                assert node.get("minItems", 0) <= 1, where
            if "enum" in node:
                assert len(node["enum"]) < 16, where
            for k, v in node.items():
                walk(v, f"{where}/{k}")
        elif isinstance(node, list):
            for i, v in enumerate(node):
                walk(v, f"{where}/{i}")

    from importlib import resources

    folder = resources.files("orientviz.io").joinpath("schema")
    names = sorted(f.name for f in folder.iterdir() if f.name.endswith(".json"))
    assert {"envelope.json", "block.json", "similarity.json"} <= set(names)
    for name in names:  # every kind's schema, also those added by other modules
        walk(load_schema(name), name)


@pytest.mark.parametrize("form", ["readable", "columnar"])
def test_valid_big_document_passes(form):
    validate(_big_docs()[form], "block.json", "big.json")


def test_unique_items_keep_their_verdict_on_arrays_of_scalars():
    from jsonschema import Draft202012Validator

    unique = Draft202012Validator({"type": "array", "uniqueItems": True})
    cases = [
        ["c"] * 70 + [1, 1.0],  # duplicates
        [f"p{i}" for i in range(100)],  # all different
        [True] + list(range(1, 80)),  # True and 1 differ in JSON
        list(range(80)) + [5.0],  # 5 and 5.0 are equal in JSON
    ]
    for items in cases:
        reduced, _ = reduce_document(items)
        assert len(reduced) < len(items)
        assert unique.is_valid(reduced) == unique.is_valid(items), items[:3]
