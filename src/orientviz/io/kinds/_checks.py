"""Row checks of the frame kinds' loaders: fail at the first offending row of a table."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from ..tables import Table


def reject_first(
    table: Table, flagged: ArrayLike, field: str, message: Callable[[int], str]
) -> None:
    """Raise an :class:`~orientviz.errors.InputError` at the first flagged row, if any.

    Parameters
    ----------
    table : Table
        The table the rows belong to; the error names the row in the form the file used
        (``points[3].X`` or ``points.X[3]``).
    flagged : array_like of bool, shape (n,), or of int, shape (k,)
        A mask over the table's rows, or the indices of the offending rows (first = the
        one reported).
    field : str
        The field named in the error.
    message : callable
        ``message(row) -> str``: the one-line problem of that row.

    Raises
    ------
    InputError
        At ``table[row].field`` for the first flagged row.
    """
    flagged = np.asarray(flagged)
    rows = np.flatnonzero(flagged) if flagged.dtype == bool else flagged.reshape(-1)
    if rows.size:
        row = int(rows[0])
        raise table.fail(row, field, message(row))
