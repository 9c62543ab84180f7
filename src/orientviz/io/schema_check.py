"""A quick yes/no check of a document against a shipped schema, without :mod:`jsonschema`.

:func:`conforms` answers "does ``doc`` satisfy schema ``name``?" for the Draft 2020-12
keywords the shipped schemas use (``type``, ``enum``, ``const``, ``properties``,
``required``, ``additionalProperties``, ``unevaluatedProperties``, ``items``,
``minItems``/``maxItems``, ``uniqueItems``, ``minLength``, the four numeric bounds,
``allOf``/``anyOf``/``oneOf``, ``if``/``then``/``else`` and ``$ref`` within and between
the shipped files), with jsonschema's meaning of each (a bool is neither a number nor an
integer, ``1.0`` is an integer, ``1 == 1.0`` but ``True != 1`` in ``enum`` and ``const``;
``unevaluatedProperties`` sees the keys that ``properties``, ``additionalProperties``
and the valid branches of ``allOf``/``anyOf``/``oneOf``/``if``/``then``/``else``/``$ref``
evaluated).

It is the fast path of :func:`orientviz.io.jsonio.validate`: ``True`` means the
document is valid and jsonschema is never imported; ``False`` (the document is
invalid, or the schema uses a keyword this module does not know, or ``uniqueItems``
meets items it does not compare) sends the document to jsonschema, which finds and
words the error. A ``True`` for a document jsonschema rejects would be a bug: the test
suite compares both on every shipped file and on mutated documents
(tests/io/test_schema_check.py).
"""

from __future__ import annotations

import json
from functools import cache
from importlib import resources
from typing import Any

#: Keywords that only annotate (no effect on validity).
ANNOTATIONS = frozenset({"$schema", "$id", "$defs", "$comment", "title", "description"})
#: Keywords :func:`conforms` applies; a schema with any other keyword is not judged here.
KNOWN = ANNOTATIONS | {
    "type", "enum", "const", "properties", "required", "additionalProperties",
    "unevaluatedProperties", "items", "minItems", "maxItems", "uniqueItems", "minLength",
    "minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum", "allOf", "anyOf",
    "oneOf", "if", "then", "else", "$ref",
}  # fmt: skip


class _Unknown(Exception):
    """The schema holds something this module does not judge (jsonschema will)."""


@cache
def _schema(name: str) -> dict[str, Any]:
    res = resources.files("orientviz.io").joinpath("schema", name)
    return json.loads(res.read_text(encoding="utf-8"))


@cache
def _resolve(ref: str, base: str) -> tuple[Any, str]:
    """The subschema a ``$ref`` names (``file.json#/$defs/x``, ``#/$defs/x``, ``file.json``)
    and the file it lies in (found once per reference: the shipped schemas do not change)."""
    file, _, pointer = ref.partition("#")
    file = file or base
    if "/" in file or ":" in file:  # only the shipped files, by their plain names
        raise _Unknown(ref)
    node: Any = _schema(file)
    for part in [p for p in pointer.split("/") if p]:
        part = part.replace("~1", "/").replace("~0", "~")
        if not isinstance(node, dict) or part not in node:
            raise _Unknown(ref)
        node = node[part]
    return node, file


def _is_number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


_TYPES = {
    "object": lambda x: isinstance(x, dict),
    "array": lambda x: isinstance(x, list),
    "string": lambda x: isinstance(x, str),
    "boolean": lambda x: isinstance(x, bool),
    "null": lambda x: x is None,
    "number": _is_number,
    "integer": lambda x: (
        (isinstance(x, int) and not isinstance(x, bool))
        or (isinstance(x, float) and x.is_integer())
    ),
}


def _equal(a: Any, b: Any) -> bool:
    """JSON equality as jsonschema judges it (bools apart from numbers)."""
    if isinstance(a, str) or isinstance(b, str):
        return a == b
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_equal(x, y) for x, y in zip(a, b))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_equal(a[k], b[k]) for k in a)
    if isinstance(a, (list, dict)) or isinstance(b, (list, dict)):
        return False
    if isinstance(a, bool) or isinstance(b, bool):
        return a is b
    return a == b


def _unique(items: list) -> bool:
    """``uniqueItems`` for strings or for numbers; anything else is not judged here."""
    if all(isinstance(v, str) for v in items):
        return len(set(items)) == len(items)
    if all(_is_number(v) for v in items):
        return len(set(items)) == len(items)  # 1 == 1.0 as in jsonschema
    raise _Unknown("uniqueItems")


def _valid(x: Any, s: Any, base: str) -> bool:
    """Whether ``x`` satisfies schema ``s`` (which lies in file ``base``)."""
    if s is True:
        return True
    if s is False:
        return False
    if not isinstance(s, dict):
        raise _Unknown(s)
    if not KNOWN.issuperset(s):
        raise _Unknown(set(s) - KNOWN)
    if "$ref" in s:
        sub, file = _resolve(s["$ref"], base)
        if not _valid(x, sub, file):
            return False
    t = s.get("type")
    if t is not None and not any(_TYPES[k](x) for k in ([t] if isinstance(t, str) else t)):
        return False
    if "enum" in s and not any(_equal(x, e) for e in s["enum"]):
        return False
    if "const" in s and not _equal(x, s["const"]):
        return False
    if _is_number(x):
        if "minimum" in s and x < s["minimum"]:
            return False
        if "maximum" in s and x > s["maximum"]:
            return False
        if "exclusiveMinimum" in s and x <= s["exclusiveMinimum"]:
            return False
        if "exclusiveMaximum" in s and x >= s["exclusiveMaximum"]:
            return False
    elif isinstance(x, str):
        if "minLength" in s and len(x) < s["minLength"]:
            return False
    elif isinstance(x, list):
        if "minItems" in s and len(x) < s["minItems"]:
            return False
        if "maxItems" in s and len(x) > s["maxItems"]:
            return False
        if s.get("uniqueItems") and not _unique(x):
            return False
        if "items" in s and not all(_valid(v, s["items"], base) for v in x):
            return False
    elif isinstance(x, dict):
        if any(k not in x for k in s.get("required", ())):
            return False
        props = s.get("properties", {})
        if any(not _valid(v, props[k], base) for k, v in x.items() if k in props):
            return False
        if "additionalProperties" in s:
            extra = s["additionalProperties"]
            if any(not _valid(v, extra, base) for k, v in x.items() if k not in props):
                return False
    if "allOf" in s and not all(_valid(x, sub, base) for sub in s["allOf"]):
        return False
    if "anyOf" in s and not any(_valid(x, sub, base) for sub in s["anyOf"]):
        return False
    if "oneOf" in s and sum(_valid(x, sub, base) for sub in s["oneOf"]) != 1:
        return False
    if "if" in s:
        branch = "then" if _valid(x, s["if"], base) else "else"
        if branch in s and not _valid(x, s[branch], base):
            return False
    if "unevaluatedProperties" in s and isinstance(x, dict):
        seen = _evaluated(x, s, base)
        rest = s["unevaluatedProperties"]
        if any(not _valid(v, rest, base) for k, v in x.items() if k not in seen):
            return False
    return True


def _evaluated(x: dict, s: Any, base: str) -> set:
    """The keys of ``x`` that schema ``s`` evaluates (jsonschema's rule for
    ``unevaluatedProperties``)."""
    if not isinstance(s, dict):
        return set()
    keys: set = set()
    if "$ref" in s:
        sub, file = _resolve(s["$ref"], base)
        keys |= _evaluated(x, sub, file)
    if isinstance(s.get("properties"), dict):
        keys |= s["properties"].keys() & x.keys()
    for word in ("additionalProperties", "unevaluatedProperties"):
        if word in s:
            keys |= {k for k, v in x.items() if _valid(v, s[word], base)}
    for word in ("allOf", "oneOf", "anyOf"):
        for sub in s.get(word, ()):
            if _valid(x, sub, base):
                keys |= _evaluated(x, sub, base)
    if "if" in s:
        if _valid(x, s["if"], base):
            keys |= _evaluated(x, s["if"], base)
            if "then" in s:
                keys |= _evaluated(x, s["then"], base)
        elif "else" in s:
            keys |= _evaluated(x, s["else"], base)
    return keys


def conforms(doc: Any, name: str) -> bool:
    """True if ``doc`` satisfies the shipped schema ``name`` (e.g. ``"block.json"``).

    Parameters
    ----------
    doc : object
        A parsed JSON document (dicts, lists, str, int, float, bool, None).
    name : str
        A schema file of ``orientviz/io/schema``.

    Returns
    -------
    bool
        True: valid. False: invalid, or not judged here (a keyword or ``uniqueItems``
        items this module does not handle) — :func:`orientviz.io.jsonio.validate` then
        asks jsonschema.
    """
    try:
        return _valid(doc, _schema(name), name)
    except (_Unknown, RecursionError, TypeError, KeyError):
        return False
