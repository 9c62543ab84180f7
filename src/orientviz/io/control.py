"""Control-point files (CSV) for imported blocks.

COLMAP and BAL models carry no control: they float in their own frame. A control file
gives object coordinates for some of their points, by the point's id (for COLMAP the
POINT3D_ID, for BAL the point index)::

    id,X,Y,Z,sX,sY,sZ,role
    17,4012.331,-12.870,301.552,0,0,0,control
    230,905.104,911.733,,0.02,0.02,,control      (an XY point: Z empty)
    415,2710.2,1830.6,322.1,,,,check

``X, Y, Z`` in m (empty = not given), ``sX, sY, sZ`` σ in m (0 or empty = fixed),
``role`` ``control`` (default) or ``check``. Columns ``sX sY sZ role`` are optional.
Every broken line raises :class:`~orientviz.errors.InputError` naming file and line.
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..block import CHECK, CONTROL, Block
from ..errors import InputError
from .safeio import open_input_text, write_atomic

F64 = NDArray[np.float64]

REQUIRED = ("id", "X", "Y", "Z")
OPTIONAL = ("sX", "sY", "sZ", "role")


@dataclass
class ControlPoints:
    """Given coordinates: ``ids`` (k,), ``xyz`` (k, 3) m (NaN = not given), ``sigma``
    (k, 3) m (0 = fixed), ``role`` (k,) 1 control / 2 check, ``lines`` (k,) file lines."""

    ids: list[str]
    xyz: F64
    sigma: F64
    role: NDArray[np.int8]
    source: str = ""
    lines: list[int] | None = None


def _num(cell: str, what: str, source: str, no: int, default: float) -> float:
    cell = cell.strip()
    if not cell:
        return default
    try:
        v = float(cell)
    except ValueError:
        raise InputError(f"{what}: expected a number, got {cell!r}", source, f"line {no}") from None
    if not np.isfinite(v):
        raise InputError(f"{what}: expected a finite number, got {cell!r}", source, f"line {no}")
    return v


def read_control(path: str | os.PathLike[str]) -> ControlPoints:
    """Read a control CSV (see the module docstring).

    Raises
    ------
    InputError
        Naming the file and line: missing columns, wrong cell counts, non-numbers,
        negative σ, unknown roles, duplicate ids, points without any coordinate.
    """

    source = str(path)
    rows, head, col = csv_table(path, "a control CSV file", REQUIRED, "empty control file")
    ids, xyz, sig, role, lines = [], [], [], [], []
    for no, r in enumerate(rows[1:], start=2):
        if not any(c.strip() for c in r):
            continue
        if len(r) != len(head):
            raise InputError(f"expected {len(head)} cells, got {len(r)}", source, f"line {no}")
        ident = r[col["id"]].strip()
        if not ident:
            raise InputError("empty id", source, f"line {no}")
        if len(ident) > 256:
            raise InputError(
                f"an id of {len(ident)} characters, expected at most 256", source, f"line {no}"
            )
        if ident in ids:
            raise InputError(f"duplicate id {ident!r}", source, f"line {no}")
        p = [_num(r[col[c]], c, source, no, np.nan) for c in "XYZ"]
        if not np.any(np.isfinite(p)):
            raise InputError(f"point {ident!r}: no coordinate given", source, f"line {no}")
        s = [_num(r[col[c]], c, source, no, 0.0) if c in col else 0.0 for c in ("sX", "sY", "sZ")]
        if min(s) < 0:
            raise InputError(f"point {ident!r}: expected σ ≥ 0 m", source, f"line {no}")
        kind = r[col["role"]].strip() if "role" in col else ""
        if kind not in ("", "control", "check"):
            raise InputError(f"role: expected control or check, got {kind!r}", source, f"line {no}")
        ids.append(ident)
        xyz.append(p)
        sig.append(s)
        role.append(CHECK if kind == "check" else CONTROL)
        lines.append(no)
    return ControlPoints(
        ids, np.array(xyz, float).reshape(-1, 3), np.array(sig, float).reshape(-1, 3),
        np.array(role, np.int8), source, lines,
    )  # fmt: skip


def write_control(path: str | os.PathLike[str], control: ControlPoints) -> None:
    """Write ``control`` as a control CSV (inverse of :func:`read_control`), atomically."""
    import io

    fh = io.StringIO(newline="")
    w = csv.writer(fh)
    w.writerow([*REQUIRED, *OPTIONAL])
    for i, ident in enumerate(control.ids):
        cells = ["" if not np.isfinite(v) else repr(float(v)) for v in control.xyz[i]]
        sig = [repr(float(v)) for v in control.sigma[i]]
        w.writerow([ident, *cells, *sig, "check" if control.role[i] == CHECK else "control"])
    write_atomic(path, fh.getvalue())


def csv_table(
    path: str | os.PathLike[str],
    what: str,
    required: tuple[str, ...],
    empty: str,
    optional: str = "",
) -> tuple[list[list[str]], list[str], dict[str, int]]:
    """Rows, header and column index of a CSV with the ``required`` columns (InputError at
    line 1 naming what is missing; ``optional`` is shown in the expected header)."""
    source = str(path)
    rows = csv_rows(open_input_text(path, what), source)
    if not rows:
        raise InputError(
            f"{empty}, expected a header {','.join(required)}{optional}", source, "line 1"
        )
    head = [h.strip() for h in rows[0]]
    missing = [c for c in required if c not in head]
    if missing:
        raise InputError(f"expected columns {', '.join(required)}{optional}; missing "
                         f"{', '.join(missing)}", source, "line 1")  # fmt: skip
    return rows, head, {h: j for j, h in enumerate(head)}


def csv_rows(stream, source: str) -> list[list[str]]:
    """All rows of a CSV stream; a cell beyond the csv module's field limit, a NUL byte or
    a broken quote is one :class:`InputError` naming the line."""
    reader = csv.reader(stream)
    rows: list[list[str]] = []
    with stream:
        try:
            for row in reader:
                rows.append(row)
        except csv.Error as exc:
            where = f"line {reader.line_num}"
            raise InputError(f"not a readable CSV row ({exc})", source, where) from None
        except UnicodeDecodeError as exc:
            where = f"line {reader.line_num + 1}"
            raise InputError(f"not UTF-8 text ({exc.reason})", source, where) from None
    return rows


def apply_control(block: Block, control: ControlPoints) -> Block:
    """A copy of ``block`` whose points named in ``control`` become control/check points.

    The given coordinates go to ``points.xyz_known`` and ``points.sigma`` (a coordinate
    not given: the approximate value with σ = NaN); the approximate coordinates ``points.xyz`` stay as they are (the
    bundle starts from them). Use ``bundle_adjust(block, control="weighted")`` for σ > 0.

    Raises
    ------
    InputError
        An id that is not a point of the block (naming the control file's line).
    """
    out = block.copy()
    index = {p: i for i, p in enumerate(out.points.ids)}
    for k, ident in enumerate(control.ids):
        if ident not in index:
            where = f"line {control.lines[k]}" if control.lines else None
            raise InputError(f"point {ident!r} is not in the block", control.source or None, where)
        i = index[ident]
        out.points.role[i] = control.role[k]
        given = np.isfinite(control.xyz[k])
        # a coordinate not given keeps a finite value with σ = NaN (the model's convention)
        out.points.xyz_known[i] = np.where(given, control.xyz[k], out.points.xyz[i])
        out.points.sigma[i] = np.where(given, control.sigma[k], np.nan)
    return out
