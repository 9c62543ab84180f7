"""Strict JSON reading, JSON Schema validation and atomic writing for problem files.

Python's :mod:`json` is lenient where a problem file must not be: it accepts ``NaN``,
``Infinity`` and ``1e999`` (which becomes ``inf``) and silently keeps the last of two
equal keys. :func:`parse_json` rejects all three and reports *where* they are, as a
path like ``observations[12].x``. Schema errors are turned into the same one-line form.
Nothing here uses ``pickle`` or ``eval``.

Places inside a document are written as paths: ``points[3].X`` (array index in brackets,
object key after a dot); :func:`format_path` builds them from ``jsonschema``'s paths.
"""

from __future__ import annotations

import json
import math
import os
import re
from collections.abc import Iterable
from functools import cache
from importlib import resources
from typing import Any

import numpy as np

from ..errors import InputError
from .columns import float_values, item_types, str_lengths
from .reduce import original_path, reduce_document
from .safeio import decode_text, read_input_bytes
from .safeio import write_atomic as _write
from .schema_check import conforms

#: Base URI of the schemas shipped in ``orientviz/io/schema`` (used for ``$ref`` only,
#: nothing is fetched).
SCHEMA_BASE = "https://orientviz.invalid/schema/1/"


class _NonFinite:
    """Placeholder for NaN/Infinity found while parsing (reported with its path later)."""

    def __init__(self, token: str) -> None:
        self.token = token

    def __repr__(self) -> str:  # pragma: no cover - debugging aid
        return self.token


class _DuplicateKeys(dict):
    """A JSON object that contained the same key twice (``duplicates`` lists them)."""

    duplicates: list[str]


def _pairs_hook(pairs: list[tuple[str, Any]]) -> dict:
    seen: dict[str, Any] = {}
    dup: list[str] = []
    for k, v in pairs:
        if k in seen:
            dup.append(k)
        seen[k] = v
    if dup:
        out = _DuplicateKeys(seen)
        out.duplicates = dup
        return out
    return seen


def _parse_float(text: str) -> float | _NonFinite:
    value = float(text)
    return value if math.isfinite(value) else _NonFinite(text)


def _parse_int(text: str) -> int | _NonFinite:
    """Integers beyond the float range (or too long to convert) are not usable numbers."""
    if len(text) > 310:
        return _NonFinite(text[:12] + "...")
    value = int(text)
    return value if abs(value) < 1e308 else _NonFinite(text[:12] + "...")


def format_path(path: Iterable[str | int]) -> str:
    """Format a JSON path as ``observations[12].x`` (empty string for the document)."""
    out = ""
    for part in path:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += f".{part}" if out else str(part)
    return out


#: Longest string accepted anywhere in a problem file (characters); ids are shorter still
#: (:data:`orientviz.io.tables.MAX_ID_LENGTH`).
MAX_TEXT_LENGTH = 100_000


def text_problem(text: str, limit: int = MAX_TEXT_LENGTH) -> str | None:
    """Why ``text`` cannot be used (too long, a lone UTF-16 surrogate), or None."""
    if len(text) > limit:
        return f"a text of {len(text)} characters, expected at most {limit}"
    if not text.isascii():
        try:
            text.encode("utf-8")
        except UnicodeEncodeError as exc:
            return (
                f"a character that is not valid Unicode text ({text[exc.start]!r} at "
                f"position {exc.start}: a lone UTF-16 surrogate)"
            )
    return None


_PLAIN = (float, int, bool, type(None))


def _find_bad(node: Any, path: list[str | int]) -> tuple[list[str | int], str] | None:
    """First NaN/inf placeholder, duplicated key or unusable text in document order."""
    hit = _bad(node)
    if hit is None:
        return None
    rev, message = hit
    return path + rev[::-1], message


def _bad(node: Any) -> tuple[list[str | int], str] | None:
    """The walk of :func:`_find_bad`: the path comes back reversed (built only on a hit)."""
    t = type(node)
    if t is str:
        if node.isascii() and len(node) <= MAX_TEXT_LENGTH:  # the usual case, inline
            return None
        why = text_problem(node)
        return ([], why) if why else None
    if t is _NonFinite:
        return [], (
            f"{node.token} is not a finite number (JSON has no NaN or Infinity; "
            "leave the field out or use null where that is allowed)"
        )
    if t is dict or t is _DuplicateKeys:
        if t is _DuplicateKeys:
            return [], f"duplicate key {node.duplicates[0]!r} in one object"
        for k, v in node.items():
            if not (k.isascii() and len(k) <= 1000):
                why = text_problem(k, 1000)
                if why:
                    return [k[:40].encode("utf-8", "backslashreplace").decode()], f"key with {why}"
            if type(v) in _PLAIN:
                continue
            hit = _bad(v)
            if hit:
                hit[0].append(k)
                return hit
    elif t is list:
        for i, v in enumerate(node):
            if type(v) in _PLAIN:
                continue
            hit = _bad(v)
            if hit:
                hit[0].append(i)
                return hit
    return None


def _suspect(node: Any) -> bool:
    """True if a document parsed without the number hooks may hold anything
    :func:`_find_bad` or the hooks object to: a non-finite float or an integer beyond the
    float range, a NaN/Infinity placeholder, a duplicated key, a non-ASCII or very long
    text. False means the strict parse gives the same document and finds nothing."""
    t = type(node)
    if t is list:
        values: Iterable[Any] = node
        if len(node) > 16:  # a long column: judged in C when it holds one type
            kinds = item_types(node)
            if kinds == {float}:  # (the values are read again by the tables)
                return not np.isfinite(float_values(node)).all()
            if kinds == {str}:
                return not "".join(node).isascii() or str_lengths(node).max() > MAX_TEXT_LENGTH
            if kinds == {int}:
                return not (-1e308 < min(node) and max(node) < 1e308)
    elif t is dict:
        for k in node:
            if not k.isascii() or len(k) > 1000:
                return True
        values = node.values()
    else:
        values = (node,)
    for v in values:
        tv = type(v)
        if tv is float:
            if v - v != 0.0:  # inf or NaN
                return True
        elif tv is str:
            if not v.isascii() or len(v) > MAX_TEXT_LENGTH:
                return True
        elif tv is int:
            if not -1e308 < v < 1e308:
                return True
        elif tv is bool or v is None:
            continue
        elif tv is list or tv is dict:
            if _suspect(v):
                return True
        else:  # a placeholder, an object with duplicated keys
            return True
    return False


def parse_json(text: str, source: str) -> Any:
    """Parse JSON text strictly.

    Parameters
    ----------
    text : str
        The document.
    source : str
        Name of the file (for messages).

    Returns
    -------
    object
        The parsed document (dicts, lists, str, int, float, bool, None).

    Raises
    ------
    InputError
        ``"<source>: line 3, column 7: malformed JSON: Expecting ',' delimiter"``, or the
        path of a NaN/Infinity/overflowing number or of a duplicated key.
    """
    try:
        # numbers parsed in C first; the strict hooks only when something is suspect
        # (the same document then, and the same first problem)
        try:
            doc = json.loads(text, parse_constant=_NonFinite, object_pairs_hook=_pairs_hook)
            strict = _suspect(doc)
        except json.JSONDecodeError:
            raise
        except ValueError:  # an integer too long for int()
            strict = True
        if strict:
            doc = json.loads(
                text,
                parse_constant=_NonFinite,
                parse_float=_parse_float,
                parse_int=_parse_int,
                object_pairs_hook=_pairs_hook,
            )
    except json.JSONDecodeError as exc:
        raise InputError(
            f"malformed JSON: {exc.msg}", source, f"line {exc.lineno}, column {exc.colno}"
        ) from None
    except RecursionError:
        raise InputError("malformed JSON: nested too deeply", source) from None
    bad = _find_bad(doc, []) if strict else None
    if bad is not None:
        raise InputError(bad[1], source, format_path(bad[0]) or "document")
    return doc


def read_json_file(path: str | os.PathLike[str]) -> Any:
    """Read and strictly parse a JSON file; every failure is an :class:`InputError`.

    The file is checked first (:func:`orientviz.io.safeio.check_input_file`: a regular
    file within the size limit).
    """
    source = str(path)
    raw = read_input_bytes(path, "a JSON problem file")
    _refuse_dense_structure(raw, source)
    return parse_json(decode_text(raw, source, "a JSON problem file", "utf-8-sig"), source)


#: Python needs about this many bytes per JSON object or array (an empty dict: 64).
_BYTES_PER_CONTAINER = 64


def _refuse_dense_structure(raw: bytes, source: str) -> None:
    """Refuse a file whose objects/arrays would need > 10 × its size in memory.

    A problem file has one object per table row (≥ 30 bytes each); ``[{},{},…]`` has one
    per 3 bytes and would take 20 × the file in Python objects. Files under 1 MB pass.
    """
    if len(raw) < 2**20:
        return
    byte = np.frombuffer(raw, dtype=np.uint8)  # counted by NumPy: ~3 × bytes.count's speed
    n = int(np.count_nonzero(byte == ord("{"))) + int(np.count_nonzero(byte == ord("[")))
    if n * _BYTES_PER_CONTAINER > 10 * len(raw):
        raise InputError(
            f"{n} JSON objects/arrays in {len(raw)} bytes: far more structure than a problem "
            f"file has (reading it would take about {n * _BYTES_PER_CONTAINER / 2**20:.0f} MB)",
            source,
        )


# --------------------------------------------------------------------------- schemas
@cache
def load_schema(name: str) -> dict[str, Any]:
    """A schema shipped in ``orientviz/io/schema/<name>`` (parsed once)."""
    res = resources.files("orientviz.io").joinpath("schema", name)
    return json.loads(res.read_text(encoding="utf-8"))


@cache
def _registry():
    from referencing import Registry, Resource

    folder = resources.files("orientviz.io").joinpath("schema")
    entries = []
    for item in folder.iterdir():
        if item.name.endswith(".json"):
            schema = json.loads(item.read_text(encoding="utf-8"))
            entries.append((SCHEMA_BASE + item.name, Resource.from_contents(schema)))
    return Registry().with_resources(entries)


#: The optional format checkers' packages that jsonschema's format module imports when
#: they are installed (rfc3987_syntax builds a parser grammar at import; isoduration
#: imports arrow); orientviz's schemas use no ``format`` keyword.
FORMAT_PACKAGES = ("rfc3987_syntax", "rfc3987", "isoduration", "rfc3339_validator",
                   "rfc3986_validator", "webcolors", "uri_template", "jsonpointer", "fqdn",
                   "idna")  # fmt: skip


def import_jsonschema():
    """Import :mod:`jsonschema` without its optional format checkers.

    orientviz's schemas use no ``format`` keyword (and validate without a format
    checker), so the packages of :data:`FORMAT_PACKAGES` are kept out for the duration
    of jsonschema's own import (they stay importable for anyone else afterwards). The
    test suite and the book's build import jsonschema this way before nbformat does
    (nbformat's notebook schemas use no ``format`` keyword either).

    Returns
    -------
    module
        :mod:`jsonschema` (the one already imported, if any).
    """
    import sys

    if "jsonschema" in sys.modules:
        return sys.modules["jsonschema"]
    blocked = [name for name in FORMAT_PACKAGES if name not in sys.modules]
    for name in blocked:
        sys.modules[name] = None  # type: ignore[assignment]
    try:
        import jsonschema
    finally:
        for name in blocked:
            if sys.modules.get(name, 0) is None:
                del sys.modules[name]
    return jsonschema


@cache
def validator_for(name: str):
    """A Draft 2020-12 validator for schema file ``name`` (with ``$ref`` resolution).

    The shipped schemas are package data, checked against the Draft 2020-12 meta-schema
    by the test suite (tests/io/test_problem_files.py), not at every start.
    """
    Draft202012Validator = import_jsonschema().Draft202012Validator

    return Draft202012Validator(load_schema(name), registry=_registry())


def _json_type(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, (int, float)):
        return "a number"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, list):
        return "an array"
    return "an object"


def _short(value: Any, limit: int = 40) -> str:
    text = json.dumps(value, default=str)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _describe(error) -> tuple[list[str | int], str]:
    """Turn a jsonschema ValidationError into (path, one-line message)."""
    path = list(error.absolute_path)
    v, inst, arg = error.validator, error.instance, error.validator_value
    if v == "required":
        missing = [k for k in arg if isinstance(inst, dict) and k not in inst]
        return path, f"missing field {missing[0]!r}" if missing else error.message
    if v in ("additionalProperties", "unevaluatedProperties"):
        # jsonschema names the offending keys in its message: "('a', 'b' were unexpected)"
        found = re.search(r"\((.*) (?:was|were) unexpected\)", error.message)
        names = re.findall(r"'((?:[^'\\]|\\.)*)'", found.group(1)) if found else []
        if not names and isinstance(inst, dict):
            allowed = set(error.schema.get("properties", {}))
            names = [k for k in inst if k not in allowed]
        name = names[0] if names else "?"
        return path + [name], f"unexpected field {name!r}"
    if v == "type":
        want = arg if isinstance(arg, str) else " or ".join(arg)
        return path, f"expected {want}, got {_json_type(inst)} ({_short(inst)})"
    if v == "enum":
        opts = ", ".join(json.dumps(a) for a in arg)
        return path, f"expected one of {opts}, got {_short(inst)}"
    if v == "const":
        return path, f"expected {json.dumps(arg)}, got {_short(inst)}"
    if v in ("minItems", "maxItems"):
        n = len(inst) if isinstance(inst, list) else "?"
        word = "at least" if v == "minItems" else "at most"
        return path, f"expected {word} {arg} item(s), got {n}"
    if v in ("minimum", "exclusiveMinimum", "maximum", "exclusiveMaximum"):
        op = {"minimum": "≥", "exclusiveMinimum": ">", "maximum": "≤", "exclusiveMaximum": "<"}
        return path, f"expected a number {op[v]} {arg}, got {_short(inst)}"
    if v == "minLength":
        return path, f"expected a non-empty string, got {_short(inst)}"
    if v == "minProperties":
        return path, "expected a non-empty object"
    return path, error.message if len(error.message) < 120 else error.message[:117] + "..."


def _order(error) -> tuple:
    key = []
    for part in error.absolute_path:
        key.append((0, part, "") if isinstance(part, int) else (1, 0, str(part)))
    # prefer structural problems (missing/extra fields) at the same place
    rank = 0 if error.validator in ("required", "additionalProperties") else 1
    return (tuple(key), rank)


def validate(
    doc: Any, schema_name: str, source: str, reduced: tuple[Any, dict] | None = None
) -> None:
    """Validate ``doc`` against a shipped schema; raise one :class:`InputError` if invalid.

    The first error in document order is reported, as ``"<source>: <path>: <problem>"``.
    Long arrays are first reduced to representative items
    (:func:`orientviz.io.reduce.reduce_document`, exact for the keywords our schemas use;
    ``reduced``: that reduction when the caller has it already, for several schemas).
    A valid document is recognised by :func:`orientviz.io.schema_check.conforms`
    without importing jsonschema; jsonschema judges the rest and words the error.
    """
    reduced, maps = reduced if reduced is not None else reduce_document(doc)
    if conforms(reduced, schema_name):
        return
    errors = list(validator_for(schema_name).iter_errors(reduced))
    if not errors:
        return
    error = min(errors, key=_order)
    path, message = _describe(error)
    path = original_path(reduced, maps, path)
    raise InputError(message, source, format_path(path) or "document")


# --------------------------------------------------------------------------- writing
#: Types of JSON scalars as parsed or written (a list of only these is flat).
_SCALARS = frozenset({float, int, str, bool, type(None)})


def _is_flat(node: Any) -> bool:
    """Scalars, arrays of scalars (or of short arrays) and objects of those: one line."""
    if isinstance(node, dict):  # a row: scalars and short arrays (a columnar table is not)
        return all(
            not isinstance(v, dict) and (not isinstance(v, list) or len(v) <= 3) and _is_flat(v)
            for v in node.values()
        )
    if isinstance(node, list):
        if item_types(node) <= _SCALARS:  # a column: one pass in C
            return True
        return all(
            not isinstance(v, (dict, list))
            or (
                isinstance(v, list)
                and _is_flat(v)
                and all(not isinstance(e, (list, dict)) for e in v)
            )
            for v in node
        )
    return True


def _dump(node: Any, level: int, indent: int) -> str:
    one = lambda v: json.dumps(v, ensure_ascii=False, allow_nan=False)  # noqa: E731
    if type(node) is list and node and type(node[0]) is float and item_types(node) == {float}:
        from .float_text import float_column_json  # only when writing: reading never loads it

        return float_column_json(node, float_values(node))  # a column of numbers, in bulk
    if _is_flat(node):
        return one(node)
    pad, inner = " " * (indent * level), " " * (indent * (level + 1))
    if isinstance(node, dict):
        items = [f"{inner}{one(k)}: {_dump(v, level + 1, indent)}" for k, v in node.items()]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    items = [f"{inner}{_dump(v, level + 1, indent)}" for v in node]
    return "[\n" + ",\n".join(items) + "\n" + pad + "]"


def dumps_json(doc: Any, *, indent: int | None = 1) -> str:
    """Serialise a document: one table row (or column) per line, ``allow_nan=False``.

    Objects and arrays that hold only scalars (a row, a column, ``units``) stay on one
    line; everything else is indented by ``indent`` spaces (None: all on one line).
    A NaN slipping through is a bug, not output: it raises ``ValueError``.
    """
    if indent is None:
        return json.dumps(doc, ensure_ascii=False, allow_nan=False) + "\n"
    return _dump(doc, 0, indent) + "\n"


def write_atomic(path: str | os.PathLike[str], text: str) -> None:
    """Write ``text`` atomically (see :func:`orientviz.io.safeio.write_atomic`)."""
    _write(path, text)
