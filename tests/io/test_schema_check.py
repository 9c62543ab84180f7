"""The quick schema check (io.schema_check.conforms) says "valid" only where jsonschema does.

Compared with jsonschema's verdict on every shipped problem file in both table forms,
and on seeded random mutations of their reductions (what validate checks: a value
replaced, a key removed or added, an array emptied, shortened or given a duplicate),
against the envelope and the file's kind schema.
"""

from __future__ import annotations

import copy
import functools
import json
import zlib

import numpy as np
import pytest

from orientviz.io.datasets import list_datasets, load_dataset
from orientviz.io.jsonio import validator_for
from orientviz.io.problem import dumps_problem
from orientviz.io.reduce import reduce_document
from orientviz.io.registry import get_kind
from orientviz.io.schema_check import conforms

NAMES = list_datasets()
VALUES = [
    None, True, False, 0, 1, -1, 0.0, 1.0, 2.5, -0.5, 1e308, "", "x", "opk", "block",
    "fixed", "tie", [], {}, [1.0], [1.0, 2.0], [None, None, None], [1.0, 2.0, 3.0],
    {"id": "p"}, ["a", "a"], [1, 1.0], [True, 1],
]  # fmt: skip


@functools.cache
def _docs(name: str) -> list[dict]:
    """The shipped file in both table forms."""
    problem = load_dataset(name)
    return [json.loads(dumps_problem(problem, columnar=c)) for c in (True, False)]


def _paths(node, prefix=()):
    out = [prefix]
    if isinstance(node, dict):
        for k, v in node.items():
            out += _paths(v, prefix + (k,))
    elif isinstance(node, list):  # long arrays: their first three and last two items
        n = len(node)
        for i in [0, 1, 2, n - 2, n - 1] if n > 5 else range(n):
            out += _paths(node[i], prefix + (i,))
    return out


def _parent(doc, path):
    for p in path[:-1]:
        doc = doc[p]
    return doc


def _mutate(doc: dict, rng: np.random.Generator) -> dict:
    """One random change of a copy of ``doc``."""
    out = copy.deepcopy(doc)
    paths = [p for p in _paths(out) if p]
    path = paths[rng.integers(len(paths))]
    parent, key = _parent(out, path), path[-1]
    what = rng.integers(6)
    if what == 0 and isinstance(parent, dict):
        del parent[key]
    elif what == 1 and isinstance(parent, dict):
        parent[str(rng.choice(["extra", "X", "sigma", "model", "free", "id"]))] = VALUES[
            rng.integers(len(VALUES))
        ]
    elif what == 2 and isinstance(parent[key], list) and parent[key]:
        parent[key] = parent[key][: int(rng.integers(len(parent[key])))]
    elif what == 3 and isinstance(parent[key], list) and parent[key]:
        parent[key].append(copy.deepcopy(parent[key][int(rng.integers(len(parent[key])))]))
    else:
        parent[key] = copy.deepcopy(VALUES[rng.integers(len(VALUES))])
    return out


def _jsonschema_valid(doc, schema: str) -> bool:
    return not any(True for _ in validator_for(schema).iter_errors(doc))


def _agree(doc, kind_schema: str) -> None:
    for schema in ("envelope.json", kind_schema):
        want = _jsonschema_valid(doc, schema)
        got = conforms(doc, schema)
        assert not got or want, f"conforms says valid, jsonschema does not ({schema})"
        assert got == want, f"conforms {got}, jsonschema {want} ({schema})"


@pytest.mark.parametrize("name", NAMES)
def test_conforms_agrees_with_jsonschema_on_shipped_files(name):
    for doc in _docs(name):
        schema = get_kind(doc["kind"]).schema
        _agree(doc, schema)
        _agree(reduce_document(doc)[0], schema)
        assert conforms(doc, schema)


@pytest.mark.parametrize("name", NAMES)
def test_conforms_agrees_with_jsonschema_on_mutated_files(name):
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    docs = [reduce_document(d)[0] for d in _docs(name)]  # what validate checks
    schema = get_kind(docs[0]["kind"]).schema
    rejected = 0
    for i in range(120):
        bad = _mutate(docs[i % len(docs)], rng)
        _agree(bad, schema)
        rejected += not conforms(bad, schema)
    assert rejected > 30  # the mutations do reach the schema's rules


def test_unknown_keyword_or_reference_is_left_to_jsonschema(monkeypatch):
    from orientviz.io import schema_check

    monkeypatch.setattr(schema_check, "_schema", lambda name: {"pattern": "^a"})
    assert not conforms("a", "x.json")
    monkeypatch.setattr(schema_check, "_schema", lambda name: {"$ref": "https://x/y.json"})
    assert not conforms("a", "x.json")


# Keyword by keyword: _valid on small schemas against jsonschema's Draft 2020-12 verdict on
# instances that sit on each keyword's edge (bool vs number, 1 vs 1.0, equal-looking
# containers, both branches of if/then/else, unevaluatedProperties behind each combinator).
KEYWORD_SCHEMAS = [
    {"enum": [1, "a", [1, 2], {"k": 1}, None, True]},
    {"const": [1, {"k": [True]}]},
    {"const": {"a": 1, "b": 2}},
    {"const": False},
    {"type": ["integer", "null"]},
    {"type": "boolean"},
    {"exclusiveMinimum": 0, "exclusiveMaximum": 2},
    {"minimum": -1, "maximum": 1},
    {"minLength": 2},
    {"uniqueItems": True},
    {"items": {"type": "number"}, "minItems": 1, "maxItems": 2},
    {"anyOf": [{"type": "string"}, {"minimum": 5}]},
    {"oneOf": [{"type": "number"}, {"type": "integer"}]},
    {"if": {"type": "number"}, "then": {"minimum": 1}, "else": {"type": "string"}},
    {"if": {"type": "object", "required": ["a"]}, "then": {"properties": {"a": {"type": "number"}}},
     "else": {"properties": {"b": {"type": "string"}}}, "unevaluatedProperties": False},
    {"anyOf": [{"properties": {"a": {}}, "required": ["a"]}, {"properties": {"b": {}}}],
     "unevaluatedProperties": False},
    {"oneOf": [{"properties": {"a": {"type": "string"}}}, {"properties": {"a": {"type": "number"}}}],
     "unevaluatedProperties": {"type": "boolean"}},
    {"allOf": [{"properties": {"a": {}}}], "additionalProperties": {"type": "number"},
     "unevaluatedProperties": False},
    {"not": {"type": "string"}},  # a keyword it does not know: refused, never judged
]  # fmt: skip
EDGE_VALUES = VALUES + [
    [1, 2], [1.0, 2.0], [2, 1], {"k": 1}, {"k": 1.0}, {"k": True}, [1, {"k": [True]}],
    [1.0, {"k": [1]}], {"a": 1, "b": 2}, {"b": 2, "a": 1.0}, {"a": 1}, {"b": "s"}, {"b": 1},
    {"a": "s", "c": True}, {"a": 1, "c": 3}, {"c": 1.5}, 5, 4.5, 2, 1.5, "ab", [["x"], ["x"]],
    [{"a": 1}, {"a": 1}], ["a", 1],
]  # fmt: skip


@pytest.mark.parametrize("schema", KEYWORD_SCHEMAS, ids=lambda s: ",".join(sorted(s)))
def test_each_keyword_judged_as_jsonschema_judges_it(schema):
    import jsonschema

    from orientviz.io.schema_check import _Unknown, _valid

    reference = jsonschema.Draft202012Validator(schema)
    judged = 0
    for value in EDGE_VALUES:
        try:
            verdict = _valid(value, schema, "block.json")
        except _Unknown:
            continue  # left to jsonschema, as conforms does
        assert verdict == reference.is_valid(value), (schema, value)
        judged += 1
    if "not" in schema:
        assert judged == 0
    else:
        assert judged >= len(EDGE_VALUES) // 2, "most edge values must be judged here"


def test_references_outside_the_shipped_files_are_left_to_jsonschema():
    from orientviz.io.schema_check import _Unknown, _valid

    for ref in ("https://example.org/s.json", "../x.json", "block.json#/no/such/node"):
        with pytest.raises(_Unknown):
            _valid(1, {"$ref": ref}, "block.json")
    with pytest.raises(_Unknown):
        _valid(1, ["not", "a", "schema"], "block.json")


def test_each_reference_is_resolved_once_and_to_the_same_node():
    from orientviz.io import schema_check

    doc = json.loads(dumps_problem(load_dataset("dbat_sxb")))
    reduced, _ = reduce_document(doc)
    assert conforms(reduced, "block.json")
    first = schema_check._resolve.cache_info()
    assert first.currsize > 0  # the block schema is made of references
    assert conforms(reduced, "block.json")
    again = schema_check._resolve.cache_info()
    assert again.misses == first.misses and again.hits > first.hits
    node, file = schema_check._resolve("frame.json#/$defs/points", "block.json")
    assert node is schema_check._schema("frame.json")["$defs"]["points"] and file == "frame.json"
