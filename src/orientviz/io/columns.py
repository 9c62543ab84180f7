"""What reading and writing ask of a long column of a document, worked out once.

Loading a problem file asks of each long column (a list of ~10⁴–10⁵ numbers or ids)
the same questions several times: the types of its items (the strict checks of
:mod:`orientviz.io.jsonio`, the schema's reduction in :mod:`orientviz.io.reduce`, the
tables of :mod:`orientviz.io.tables`), for numbers their values as an array (the strict
checks, the reduction and the tables), for strings their lengths; writing one asks them
again (the schema check before the text, the text). Inside :func:`shared_columns` — one load or one write — the answers are
kept per list object (the lists are not changed there); outside it each call works them
out afresh. The kept lists are held until the block ends, so an id names one list.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar

import numpy as np
from numpy.typing import NDArray

#: Shorter lists are answered afresh at each call (cheaper than keeping them).
MIN_SHARED = 64

_KEPT: ContextVar[dict[int, list] | None] = ContextVar("orientviz_io_columns", default=None)


@contextmanager
def shared_columns() -> Iterator[None]:
    """Keep the answers about long lists until the block ends (nests: the outer one wins)."""
    if _KEPT.get() is not None:
        yield
        return
    token = _KEPT.set({})
    try:
        yield
    finally:
        _KEPT.reset(token)


def _kept(col: list) -> list | None:
    """The record [list, item types, float values, string lengths] of ``col`` when
    answers are kept."""
    kept = _KEPT.get()
    if kept is None or len(col) < MIN_SHARED:
        return None
    record = kept.get(id(col))
    if record is None or record[0] is not col:
        record = kept[id(col)] = [col, None, None, None]
    return record


def item_types(col: list) -> frozenset[type]:
    """The types of the items of ``col`` (``bool`` is not ``int``)."""
    record = _kept(col)
    if record is None:
        return frozenset(map(type, col))
    if record[1] is None:
        record[1] = frozenset(map(type, col))
    return record[1]


def str_lengths(col: list[str]) -> NDArray[np.int64]:
    """The lengths of the strings of ``col``; read-only when kept."""
    record = _kept(col)
    if record is None:
        return np.fromiter(map(len, col), dtype=np.int64, count=len(col))
    if record[3] is None:
        lengths = np.fromiter(map(len, col), dtype=np.int64, count=len(col))
        lengths.flags.writeable = False
        record[3] = lengths
    return record[3]


def float_values(col: list) -> NDArray[np.float64]:
    """``np.array(col, dtype=float)``; read-only when kept (callers copy to change it)."""
    record = _kept(col)
    if record is None:
        return np.array(col, dtype=float)
    if record[2] is None:
        values = np.array(col, dtype=float)
        values.flags.writeable = False
        record[2] = values
    return record[2]


def made_floats(col: list, values: NDArray[np.float64]) -> None:
    """Record a list that the caller has just made from ``values``: its floats, and None
    where ``values`` is NaN. Its item types and float values are then known, not worked
    out from the list again (when answers are kept; ``values`` becomes read-only).
    """
    record = _kept(col)
    if record is None:
        return
    n_none = len(col) - int(np.count_nonzero(np.isfinite(values)))
    types = ({float} if n_none < len(col) else set()) | ({type(None)} if n_none else set())
    record[1] = frozenset(types)
    values.flags.writeable = False
    record[2] = values
