"""Shrink long arrays before JSON-Schema validation without changing its verdict.

``jsonschema`` is pure Python and spends ~10 µs per array item and keyword: a block of
100 000 observations would take minutes. Every keyword our schemas apply to the items of
a long array judges one item at a time and only by

* its JSON type (and, for objects, which keys it has; for arrays, their length),
* the extremes of its numbers (``minimum``, ``exclusiveMinimum``, …),
* the length of its strings (``minLength``) and, for enumerations of fewer than
  :data:`DISTINCT` values, the string itself.

So an item is *redundant* when every such feature it has is already shown by another
kept item. :func:`reduce_document` keeps, per feature, the first item with the most
extreme value; the reduced document is valid if and only if the original is. An error
found in it is mapped back to the original index by :func:`original_path`.

For arrays of scalars the first pair of equal items is kept as well, so ``uniqueItems``
keeps its verdict there.

Rules for schema authors (checked by ``tests/io/test_reduce.py`` on every shipped
schema): on arrays that may be longer than :data:`MIN_LENGTH` do not use ``maxItems``,
``minItems`` above 1, ``contains``, ``prefixItems``, ``uniqueItems`` on arrays of objects
or arrays, ``enum`` with ≥ :data:`DISTINCT` strings, or any keyword that relates two
items or two fields of an item (``dependentRequired``, ``if`` on a value). Small arrays
are never reduced.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .columns import float_values, item_types, str_lengths

#: Arrays up to this many items are validated as they are.
MIN_LENGTH: int = 64
#: Distinct string values kept per place (enums must have fewer values than this).
DISTINCT: int = 16
#: Items looked at one by one for an equal pair before a whole column is set against itself.
DUPLICATE_SCAN: int = 256


def _features(node: Any, path: tuple, out: list) -> None:
    """Append (key, rank) pairs describing what the schema can see of ``node``."""
    if node is None or isinstance(node, bool):
        out.append(((path, repr(node)), 0))
    elif isinstance(node, (int, float)):
        kind = "int" if isinstance(node, int) or float(node).is_integer() else "float"
        out.append(((path, kind, "min"), node))
        out.append(((path, kind, "max"), -node))
    elif isinstance(node, str):
        out.append(((path, "str", "len"), len(node)))
        out.append(((path, "str", "value", node), 0))
    elif isinstance(node, dict):
        out.append(((path, "keys", tuple(node)), 0))
        for k, v in node.items():
            _features(v, path + (k,), out)
    elif isinstance(node, list):
        out.append(((path, "len", len(node)), 0))
        for i, v in enumerate(node):
            _features(v, path + (i,), out)


def _keep_generic(items: list) -> list[int]:
    """Indices of the items that show every feature of the array (sorted); any items."""
    best: dict[tuple, tuple[Any, int]] = {}
    values_seen: dict[tuple, int] = {}
    for i, item in enumerate(items):
        feats: list = []
        _features(item, (), feats)
        for key, rank in feats:
            if len(key) == 4:  # a string value: only the first DISTINCT per place
                place = key[0]
                if key not in best:
                    n = values_seen.get(place, 0)
                    if n >= DISTINCT:
                        continue
                    values_seen[place] = n + 1
                    best[key] = (rank, i)
                continue
            old = best.get(key)
            if old is None or rank < old[0]:
                best[key] = (rank, i)
    return sorted({i for _, i in best.values()})


def _keep_numbers(items: list) -> set[int]:
    """Numbers only: the first minimum and maximum of the integral and the other values."""
    arr = float_values(items)
    out: set[int] = set()
    integral = np.isfinite(arr) & (arr == np.round(arr))
    for mask in (integral, ~integral):
        idx = np.flatnonzero(mask)
        if idx.size:
            out.add(int(idx[np.argmin(arr[idx])]))
            out.add(int(idx[np.argmax(arr[idx])]))
    return out


def _keep_strings(items: list) -> set[int]:
    """Strings only: the first shortest and the first of the first DISTINCT values."""
    lengths = str_lengths(items)
    out = {int(np.argmin(lengths))}
    first: dict[str, int] = {}  # the first DISTINCT values and where each first appears
    for i, value in enumerate(items):
        if value not in first:
            first[value] = i
            if len(first) == DISTINCT:
                break
    out.update(first.values())
    return out


def _keep_rows(items: list) -> set[int]:
    """Objects only: one item per key layout, then column by column."""
    out: set[int] = set()
    seen: set[tuple] = set()
    for i, layout in enumerate(map(tuple, items)):
        if layout not in seen:
            seen.add(layout)
            out.add(i)
    for key in dict.fromkeys(k for layout in seen for k in layout):
        rows = [i for i, d in enumerate(items) if key in d]
        values = [items[i][key] for i in rows]
        out.update(rows[j] for j in _keep(values))
    return out


def _first_duplicate(items: list, types: set | None = None) -> set[int]:
    """Scalars only: the first pair of equal items in JSON's sense (1 == 1.0, True != 1).

    Keeping such a pair makes ``uniqueItems`` judge the reduced array as the original.
    ``types``: the items' types when known; an array of only strings or only floats
    whose first :data:`DUPLICATE_SCAN` items are all different is then recognised by
    one set when it has no equal pair at all (Python's equality is JSON's there).
    """
    one_set = types is not None and (types == {str} or types == {float})
    seen: dict[tuple, int] = {}
    for i, v in enumerate(items):
        if i == DUPLICATE_SCAN and one_set and len(set(items)) == len(items):
            return set()
        if isinstance(v, bool) or v is None:
            key: tuple = ("lit", v)
        elif isinstance(v, (int, float)):
            key = ("num", float(v))
        else:
            key = ("str", v)
        j = seen.setdefault(key, i)
        if j != i:
            return {j, i}
    return set()


def _keep(items: list) -> list[int]:
    """Indices of the items that show every feature of the array (sorted).

    Fast paths for columns of numbers or strings and for rows (objects) give the same
    set of features as :func:`_keep_generic`, which handles everything else. For arrays
    of scalars the first pair of equal items is kept too (for ``uniqueItems``).
    """
    types = item_types(items)
    if types <= {int, float, str, bool, type(None)}:
        return sorted(set(_keep_scalars(items, types)) | _first_duplicate(items, types))
    if types == {dict}:
        return sorted(_keep_rows(items))
    return _keep_generic(items)


def _keep_scalars(items: list, types: set) -> list[int]:
    """Representatives of an array of scalars (see :func:`_keep`)."""
    if types <= {int, float}:
        return sorted(_keep_numbers(items))
    if types == {str}:
        return sorted(_keep_strings(items))
    if types <= {int, float, type(None)}:
        nums = [i for i, v in enumerate(items) if v is not None]
        out = {items.index(None)} | {nums[j] for j in _keep_numbers([items[i] for i in nums])}
        return sorted(out)
    return _keep_generic(items)


def reduce_document(doc: Any) -> tuple[Any, dict[int, list[int]]]:
    """A copy of ``doc`` with long arrays reduced, and the index maps of those arrays.

    Returns
    -------
    reduced : object
        Same structure; long arrays hold only representative items (shared, not copied).
    maps : dict
        ``id(reduced array) -> original indices`` of its items.
    """
    maps: dict[int, list[int]] = {}

    def walk(node: Any) -> Any:
        if isinstance(node, dict):
            return {k: walk(v) for k, v in node.items()}
        if isinstance(node, list):
            if len(node) > MIN_LENGTH:
                keep = _keep(node)
                out = [walk(node[i]) for i in keep]
                maps[id(out)] = keep
                return out
            return [walk(v) for v in node]
        return node

    return walk(doc), maps


def original_path(reduced: Any, maps: dict[int, list[int]], path: list) -> list:
    """Translate an error path in the reduced document to the original document."""
    out, node = [], reduced
    for part in path:
        if isinstance(node, list) and isinstance(part, int) and id(node) in maps:
            out.append(maps[id(node)][part])
        else:
            out.append(part)
        try:
            node = node[part]
        except (KeyError, IndexError, TypeError):
            node = None
    return out
