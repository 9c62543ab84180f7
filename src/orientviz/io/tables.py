"""Tables in problem files: the readable and the compact (columnar) form.

Every table of a problem file (cameras, images, points, observations, …) may be written

* **readable**, one object per row::

      "observations": [{"image": "101", "point": "7", "x": -3.215, "y": 88.01}, ...]

* **columnar** (compact, for big blocks), one array per field::

      "observations": {"image": ["101", ...], "point": ["7", ...], "x": [...], "y": [...]}

Both forms hold the same fields; the JSON Schema checks the types, :class:`Table` checks
what a schema cannot (equal column lengths, unknown and duplicate ids) and knows how to
name a place in either form (``observations[12].x`` or ``observations.x[12]``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError
from .columns import float_values, item_types, made_floats

#: Marker for a field without default (it must be present).
REQUIRED = object()
#: Longest id (characters) of an image, point or camera.
MAX_ID_LENGTH = 256


@dataclass
class Table:
    """A table of a problem file, normalised to columns.

    Attributes
    ----------
    name : str
        The table's key in the document (``"points"``).
    columns : dict of str to list
        One list per field, all of length ``n``; absent optional fields hold their default.
    n : int
        Number of rows.
    columnar : bool
        The form the table was written in (for messages).
    source : str
        The file, for messages.
    """

    name: str
    columns: dict[str, list[Any]]
    n: int
    columnar: bool
    source: str

    def where(self, row: int, field: str | None = None) -> str:
        """The place of a cell: ``points[3].X`` (readable) or ``points.X[3]`` (columnar)."""
        if field is None:
            return f"{self.name}[{row}]"
        if self.columnar:
            return f"{self.name}.{field}[{row}]"
        return f"{self.name}[{row}].{field}"

    def fail(self, row: int, field: str | None, message: str) -> InputError:
        """An :class:`InputError` at a cell (raise it)."""
        return InputError(message, self.source, self.where(row, field))

    def __len__(self) -> int:
        return self.n

    def strings(self, field: str) -> list[str]:
        """A column of ids/names as ``str``."""
        col = self.columns[field]
        if _only(col, str):  # as read from JSON: already str
            return list(col)
        return [str(v) for v in col]

    def floats(self, field: str, scale: float = 1.0) -> NDArray[np.float64]:
        """A number column as floats times ``scale``; JSON ``null`` becomes NaN."""
        col = self.columns[field]
        if _only(col, float):  # the usual column: one conversion in C
            return float_values(col) * scale
        return np.array([np.nan if v is None else float(v) for v in col], dtype=float) * scale

    def ints(self, field: str, missing: int = -1) -> NDArray[np.int64]:
        """A column of whole numbers (e.g. strip numbers); JSON ``null`` becomes ``missing``.

        A number that is not whole or lies outside ± 2⁵³ (where floats stop counting in
        ones; JSON readers may have parsed it as a float) names its place.
        """
        out = np.empty(self.n, dtype=np.int64)
        for i, v in enumerate(self.columns[field]):
            if v is None:
                out[i] = missing
                continue
            if isinstance(v, bool) or not isinstance(v, (int, float)) or v != v:
                raise self.fail(i, field, f"expected a whole number, got {v!r}")
            if abs(v) > 2**53 or int(v) != v:
                raise self.fail(i, field, f"expected a whole number within ±2^53, got {v!r}")
            out[i] = int(v)
        return out

    def vectors(self, field: str, size: int, scale: float = 1.0) -> NDArray[np.float64]:
        """A column whose cells are a number or an array of ``size`` numbers (or null).

        A single number is broadcast to all ``size`` components; null gives NaN.
        """
        col = self.columns[field]
        if _only(col, float):  # one number per cell (the usual σ column): broadcast
            return np.repeat(float_values(col)[:, None], size, axis=1) * scale
        out = np.full((self.n, size), np.nan)
        for i, v in enumerate(col):
            if v is None:
                continue
            if isinstance(v, list):
                if len(v) != size:
                    raise self.fail(i, field, f"expected {size} numbers, got {len(v)}")
                out[i] = [np.nan if e is None else float(e) for e in v]
            else:
                out[i] = float(v)
        return out * scale

    def index(self, field: str = "id", what: str | None = None) -> dict[str, int]:
        """Map the ids in ``field`` to row numbers, rejecting duplicates with their place."""
        keys = self.strings(field)
        seen = dict(zip(keys, range(len(keys))))
        if len(seen) == len(keys) and max(map(len, keys), default=0) <= MAX_ID_LENGTH:
            return seen  # unique and short: the loop below would give the same map
        seen = {}
        for i, key in enumerate(keys):
            if len(key) > MAX_ID_LENGTH:
                raise self.fail(
                    i, field, f"an id of {len(key)} characters, expected at most {MAX_ID_LENGTH}"
                )
            if key in seen:
                raise self.fail(
                    i,
                    field,
                    f"duplicate {what or self.name} id {key!r} (first at {self.where(seen[key], field)})",
                )
            seen[key] = i
        return seen

    def lookup(self, field: str, ids: dict[str, int], what: str) -> NDArray[np.int64]:
        """Indices of the ids in column ``field`` in ``ids``; unknown ids name their place."""
        col = self.columns[field]
        try:  # every cell one of the ids (so a str): one pass in C
            return np.fromiter(map(ids.get, col), np.int64, len(col)).reshape(self.n)
        except TypeError:  # an unknown id (None), a cell that is not a string
            pass
        keys = self.strings(field)
        out = np.empty(self.n, dtype=np.int64)
        for i, key in enumerate(keys):
            j = ids.get(key)
            if j is None:
                raise self.fail(i, field, f"unknown {what} id {key!r}")
            out[i] = j
        return out


def _only(col: list, kind: type) -> bool:
    """Whether every cell of a column is exactly of type ``kind`` (bool is not int)."""
    return item_types(col) <= {kind}


def read_table(
    doc: dict[str, Any], name: str, fields: dict[str, Any], source: str, *, optional: bool = False
) -> Table:
    """Normalise table ``name`` of a (schema-validated) document to columns.

    Parameters
    ----------
    doc : dict
        The document (or a sub-object holding the table).
    name : str
        Key of the table; also the prefix of places in messages.
    fields : dict of str to default
        Field names with their default for absent values, or :data:`REQUIRED`.
    source : str
        The file, for messages.
    optional : bool
        If True a missing table is an empty table.

    Returns
    -------
    Table
    """
    node = doc.get(name.rsplit(".", 1)[-1])
    if node is None:
        if optional:
            return Table(name, {f: [] for f in fields}, 0, False, source)
        raise InputError(f"missing table {name!r}", source, "document")
    if isinstance(node, list):
        n = len(node)
        cols: dict[str, list[Any]] = {}
        for f, default in fields.items():
            col = []
            for i, row in enumerate(node):
                if not isinstance(row, dict):
                    raise InputError("expected an object", source, f"{name}[{i}]")
                if f in row:
                    col.append(row[f])
                elif default is REQUIRED:
                    raise InputError(f"missing field {f!r}", source, f"{name}[{i}]")
                else:
                    col.append(default)
            cols[f] = col
        return Table(name, cols, n, False, source)
    if isinstance(node, dict):
        lengths = {f: len(v) for f, v in node.items() if isinstance(v, list)}
        if not lengths:
            raise InputError("expected an array of rows or an object of columns", source, name)
        first = next(iter(lengths))
        n = lengths[first]
        for f, m in lengths.items():
            if m != n:
                raise InputError(
                    f"column has {m} entries but column {first!r} has {n}", source, f"{name}.{f}"
                )
        cols = {}
        for f, default in fields.items():
            if f in node:
                cols[f] = node[f]  # the document's list (tables do not change their columns)
            elif default is REQUIRED:
                raise InputError(f"missing column {f!r}", source, name)
            else:
                cols[f] = [default] * n
        return Table(name, cols, n, True, source)
    raise InputError("expected an array of rows or an object of columns", source, name)


def write_table(columns: dict[str, list[Any]], columnar: bool) -> list[dict] | dict[str, list]:
    """Build a table node from columns; in the readable form ``None`` cells are left out.

    Parameters
    ----------
    columns : dict of str to list
        Equal-length columns of JSON values (numbers, strings, lists, None). In the
        compact form the node holds these lists themselves, not copies.
    columnar : bool
        Write the compact form (object of arrays) instead of one object per row.
    """
    if columnar:  # the lists themselves: what the writer recorded of them stays theirs
        return {
            k: v if type(v) is list else list(v)
            for k, v in columns.items()
            if any(e is not None for e in v)
        }
    n = len(next(iter(columns.values()))) if columns else 0
    return [{k: v[i] for k, v in columns.items() if v[i] is not None} for i in range(n)]


def json_number(value: float, digits: int = 15) -> float | None:
    """A float for JSON: NaN → None, otherwise rounded to ``digits`` significant digits.

    15 significant digits keep 1 nm at 10⁶ m and remove the last-bit noise of unit
    conversions (mm ↔ m, gon ↔ rad), so that a value with ≤ 15 digits read from a file
    is written back exactly as it was.
    """
    v = float(value)
    if not np.isfinite(v):
        return None
    return float(f"{v:.{digits}g}")


#: Exact powers of ten as doubles (10**0 … 10**22): a significand divided by one of them
#: is the double nearest to the decimal number, as ``float()`` of its text.
_POW10 = np.array([10.0**k for k in range(23)])


def json_numbers(values, digits: int = 15) -> list[float | None]:
    """:func:`json_number` over a 1-D array (the same floats; mostly without text).

    With 15 digits, a value v in [1e-8, 1e15) is scaled to its 15-digit significand
    s = v · 10**k (k = 14 − ⌊log10 v⌋ ≤ 22, so 10**k is exact). The product is rounded
    to a multiple of at most 1/8 below 1e15, on a grid that holds the half-integers, and
    rounding is monotone: unless the rounded s is a half-integer it lies on the same
    side of every half-integer as the exact product, so rint(s) is the significand that
    ``"%.15g"`` writes, and rint(s) / 10**k, one correctly rounded division, is the
    double that ``float()`` reads back from that text. The other values (a half-integer
    s, outside that range, zeros, other ``digits``) go through the text as
    :func:`json_number` does.
    """
    arr = np.asarray(values, dtype=float).reshape(-1)
    if arr.size == 0:
        return []
    out = np.full(arr.size, np.nan)
    slow = np.isfinite(arr)
    if digits == 15:
        with np.errstate(divide="ignore", invalid="ignore"):
            a = np.abs(arr)
            k = 14 - np.floor(np.log10(a))
            ok = slow & (k >= 0) & (k <= 22)
            kk = np.where(ok, k, 0).astype(np.intp)
            sig = a * _POW10[kk]
            r = np.rint(sig)
            ok &= (sig >= 1e14) & (sig < 1e15) & (sig - np.floor(sig) != 0.5)
            out[ok] = np.copysign(r[ok] / _POW10[kk[ok]], arr[ok])
        slow &= ~ok
    idx = np.flatnonzero(slow)
    if idx.size:
        fmt = f"%.{int(digits)}g\n"
        text = (fmt * idx.size) % tuple(arr[idx].tolist())
        out[idx] = np.array(text.split(), dtype=float)
    res: list[float | None] = out.tolist()
    for i in np.flatnonzero(~np.isfinite(arr)).tolist():
        res[i] = None
    made_floats(res, out)  # a writer's checks and text need not read the list again
    return res
