"""JSON text of a long column of floats in bulk: the same text as ``json.dumps``.

``json.dumps`` writes a float as ``repr`` does: the shortest decimal that reads back as
the same double, in fixed notation from 1e-4 up to 1e16, with ``.0`` added to whole
numbers, one number at a time. :func:`float_column_json` writes the same text for a
whole column in a few array operations, and leaves to ``repr`` the numbers where it
cannot show that the text is the same.

Why the text is the same. For a double v in [10^e, 10^(e+1)) let D be the 15-digit
integer rint(v · 10^(14−e)). If D / 10^(14−e), one correctly rounded division of exact
operands (D < 2⁵³, 10^k exact for k ≤ 22), is v again, then the decimal D·10^(e−14)
reads back as v, and it is the only 15-digit decimal that does: two of them lie at
least 10^(e−14) apart, more than the width of v's rounding interval (≤ 2.3·10^(e−15)).
A shorter decimal that reads back as v is a 15-digit one with trailing zeros, so the
shortest is D with its trailing zeros removed — the digits ``repr`` writes. Numbers that
fail the check (16 or 17 digits), lie outside [1e-4, 1e15) or are not finite are written
by ``repr`` (or refused, as ``json.dumps(allow_nan=False)`` refuses them).
"""

from __future__ import annotations

import json
import math
from functools import cache

import numpy as np

#: Shorter columns are written by ``json.dumps`` (the arrays' set-up would cost more).
MIN_BULK = 64
#: Characters of a row: the sign, 21 for the digits and the point, the separator ", ".
_WIDTH = 24


@cache
def _tables() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Exact powers of ten 10**0 … 10**22; the four digits of 0 … 9999 as characters in
    one 32-bit word ("0042"); how many of those are trailing zeros; and which of a row's
    characters are written, by 2 × (characters after the sign) + (1 if negative)."""
    pow10 = np.array([10.0**k for k in range(23)])
    i = np.arange(10_000)
    chunks = (i[:, None] // np.array([1000, 100, 10, 1]) % 10 + ord("0")).astype(np.uint8)
    trailing = sum((i % 10**j == 0).astype(np.intp) for j in range(1, 5))
    keep = np.array(
        [[s == 1] + [j < m for j in range(21)] + [True, True] for m in range(22) for s in (0, 1)]
    )
    return pow10, chunks.view(np.uint32)[:, 0], trailing, keep.view(np.uint64)


def float_column_json(values: list[float], array: np.ndarray | None = None) -> str:
    """``json.dumps(values, allow_nan=False)`` for a list of Python floats.

    Parameters
    ----------
    values : list of float
        Every item exactly a ``float`` (no int, bool or None).
    array : ndarray, optional
        ``np.array(values)`` when the caller has it.

    Returns
    -------
    str
        ``"[1.5, -0.25, 3.0]"``: the same text as ``json.dumps``.

    Raises
    ------
    ValueError
        If a value is NaN or infinite (as ``json.dumps(allow_nan=False)``).
    """
    n = len(values)
    if n < MIN_BULK:
        return json.dumps(values, allow_nan=False)
    v = np.array(values, dtype=float) if array is None else array
    first = values[0]
    if math.isfinite(first) and (v == first).all() and (np.signbit(v) == np.signbit(first)).all():
        return "[" + ", ".join([repr(first)] * n) + "]"  # one value (a column of σ)
    pow10, chunk_text, trailing, keep_rows = _tables()
    a = np.abs(v)
    with np.errstate(divide="ignore", invalid="ignore"):
        e = np.floor(np.log10(a))
    # the 15-digit significand D, checked by reading it back
    ok = (e >= -4) & (e <= 14)  # fixed notation, D / 10**k with k = 14 - e in 0 … 18
    k = np.where(ok, 14 - e, 0).astype(np.intp)
    D = np.rint(a * pow10[k])
    ok &= (D >= 1e14) & (D < 1e15) & (D / pow10[k] == a)
    zero = a == 0.0
    ok |= zero
    slow = np.flatnonzero(~ok)
    if slow.size * 4 > n:  # mostly 16–17 digits: one call in C is quicker
        return json.dumps(values, allow_nan=False)
    if slow.size and not np.isfinite(v[slow]).all():
        return json.dumps(values, allow_nan=False)  # raises, as json.dumps does
    D[~ok] = 0.0
    e = np.where(ok & ~zero, e, 0).astype(np.intp)
    # rows sorted by exponent: each exponent's rows are one slice, laid out alike (the
    # exponents, -4 … 14, as int8: a stable sort of bytes is a radix sort)
    order = np.argsort(e.astype(np.int8), kind="stable")
    es = e[order]
    Di = D[order].astype(np.int64)
    chunks = (Di // 10**12, Di // 10**8 % 10**4, Di // 10**4 % 10**4, Di % 10**4)
    digits = np.empty((n, 4), np.uint32)  # D as 16 characters, the first "0"
    for j, c in enumerate(chunks):
        digits[:, j] = chunk_text[c]
    digits = digits.view(np.uint8)[:, 1:]
    rows = np.empty((n, _WIDTH), np.uint8)
    rows[:, 0] = ord("-")
    rows[:, 22:] = np.frombuffer(b", ", np.uint8)
    bounds = np.searchsorted(es, np.arange(-4, 16))
    for ei in range(-4, 15):
        lo, hi = bounds[ei + 4], bounds[ei + 5]
        if lo == hi:
            continue
        r, d = rows[lo:hi], digits[lo:hi]
        if ei >= 0:  # the integer part, the point, the rest of the digits, zeros
            r[:, 1 : 2 + ei] = d[:, : ei + 1]
            r[:, 2 + ei] = ord(".")
            r[:, 3 + ei : 17] = d[:, ei + 1 :]
            r[:, 17:22] = ord("0")
        else:  # "0.", zeros, the digits, zeros
            r[:, 1:3] = np.frombuffer(b"0.", np.uint8)
            r[:, 3 : 2 - ei] = ord("0")
            r[:, 2 - ei : 17 - ei] = d
            r[:, 17 - ei : 22] = ord("0")
    out = np.empty_like(rows)
    out[order] = rows
    # characters written after the sign: the integer part (ip), the point and the
    # fraction's digits up to the last nonzero one (at least one)
    tz = trailing[chunks[3]]
    run = chunks[3] == 0
    for c in (chunks[2], chunks[1], chunks[0]):
        tz[run] += trailing[c[run]]
        run &= c == 0
    tzo = np.empty_like(tz)
    tzo[order] = tz
    ip = np.maximum(e, 0) + 1
    nf = np.where(e >= 0, np.maximum(15 - tzo - ip, 1), 14 - tzo - e)
    keep = keep_rows[2 * (ip + 1 + nf) + np.signbit(v)].view(bool)
    if slow.size == 0:
        return "[" + out[keep].tobytes()[:-2].decode("ascii") + "]"
    keep[slow, :22] = False  # the separator only; repr's text goes before it
    ends = np.cumsum(keep.sum(axis=1))
    body = out[keep].tobytes().decode("ascii")
    parts, at = [], 0
    for i, x in zip(slow.tolist(), v[slow].tolist()):
        cut = int(ends[i]) - 2
        parts.append(body[at:cut])
        parts.append(repr(x))
        at = cut
    parts.append(body[at:])
    return "[" + "".join(parts)[:-2] + "]"
