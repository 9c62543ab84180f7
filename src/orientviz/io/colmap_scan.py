"""Vectorised scanning of large whitespace-separated text files (COLMAP's text models).

A file is read once, in chunks of whole lines (:func:`line_chunks`); each chunk is cut
into tokens by numpy (:func:`tokenize`: one comparison and one ``flatnonzero`` over the
bytes), and only the tokens a reader keeps are converted to numbers
(:func:`parse_numbers`: digits summed per token as int64, then one division by a power
of ten — exact operands up to 2**53, so the correctly rounded result, the double
Python's ``float`` reads). Tokens with a longer significand, in exponent notation or
otherwise unusual fall back to Python's ``float``/``int``. Nothing here knows COLMAP or
BAL; :mod:`orientviz.io.colmap_text` and :mod:`orientviz.io.bal` build on it.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

#: Bytes read per chunk (a chunk grows to the end of its last line).
CHUNK_BYTES: int = 4 << 20
I64 = NDArray[np.int64]
_POW10 = 10 ** np.arange(19, dtype=np.int64)
_P10F = 10.0 ** np.arange(20)
_ZERO, _DOT, _MINUS, _PLUS = 48, 46, 45, 43
#: Longest token (sign, digits and point) converted without Python.
_MAX_FAST = 19


@dataclass
class Chunk:
    """Whole lines of a file: ``buf`` (uint8), the 1-based number of its first line and
    the offsets of its newlines (one per line; the last byte is one)."""

    buf: NDArray[np.uint8]
    first_line: int
    newlines: I64


def _newlines(raw: bytearray, buf: NDArray[np.uint8], search: int = 256) -> I64:
    """Offsets of the newlines in ``buf`` (a view of ``raw``): the first ``search`` by
    ``find`` (memchr: fast for few long lines), the rest by numpy (many short lines)."""
    found, pos = [], -1
    for _ in range(search):
        pos = raw.find(b"\n", pos + 1, buf.size)
        if pos < 0:
            return np.array(found, dtype=np.int64)
        found.append(pos)
    rest = np.flatnonzero(buf[pos + 1 :] == 10) + (pos + 1)
    return np.concatenate([np.array(found, dtype=np.int64), rest])


def line_chunks(path: Path, chunk_bytes: int | None = None) -> Iterator[Chunk]:
    """Read ``path`` once, yielding chunks that end with a newline (one is added at the end).

    The bytes (:data:`CHUNK_BYTES` at a time unless ``chunk_bytes`` is given) are read
    into one buffer that is used again for the next chunk (no copy per chunk): a chunk
    is valid until the next one is asked for.
    """
    store = bytearray(chunk_bytes or CHUNK_BYTES)
    have = 0  # bytes of a line not yet complete, at the front of store
    line = 1
    with open(path, "rb") as f:
        while True:
            if have == len(store):  # a line longer than the buffer: a bigger one
                store = store + bytearray(len(store))
            with memoryview(store) as view:
                got = f.readinto(view[have:])
            if not got:
                break
            end = have + got
            cut = store.rfind(b"\n", 0, end) + 1
            if cut == 0:
                have = end
                continue
            buf = np.frombuffer(store, dtype=np.uint8, count=cut)
            newlines = _newlines(store, buf)
            yield Chunk(buf, line, newlines)
            line += newlines.size
            store[: end - cut] = store[cut:end]
            have = end - cut
    if have:
        buf = np.frombuffer(bytes(store[:have]) + b"\n", dtype=np.uint8)
        yield Chunk(buf, line, np.flatnonzero(buf == 10))


@dataclass
class Tokens:
    """Tokens of a chunk: ``start``/``end`` byte offsets and the chunk-local ``line`` index."""

    start: I64
    end: I64
    line: I64
    line_start: I64  # byte offset of every line of the chunk
    n_lines: int

    def __len__(self) -> int:
        return int(self.start.size)

    def first_of_line(self) -> I64:
        """Index of the first token of every line (= the next line's first if it has none)."""
        return np.searchsorted(self.line, np.arange(self.n_lines + 1))


def tokenize(buf: NDArray[np.uint8]) -> Tokens:
    """Split ``buf`` (complete lines: it ends with a newline) at ASCII whitespace and
    control characters; token k ends at the k-th separator."""
    sep = np.flatnonzero(buf <= 32)  # spaces, tabs, CR, LF and other control bytes
    nl = buf[sep] == 10
    lines = np.empty(sep.size + 1, dtype=np.int32)  # newlines before each token
    lines[0] = 0
    np.cumsum(nl, dtype=np.int32, out=lines[1:])
    start = np.empty(sep.size, dtype=np.int64)
    start[:1] = 0
    np.add(sep[:-1], 1, out=start[1:])
    end, line = sep, lines[:-1]
    keep = end > start
    if not keep.all():  # runs of separators leave empty tokens
        start, end, line = start[keep], end[keep], line[keep]
    line_start = np.concatenate([[0], sep[nl] + 1])[:-1]
    return Tokens(start, end, line, line_start, int(lines[-1]))


def token_starts(buf: NDArray[np.uint8]) -> tuple[I64, bool]:
    """Start offsets of the tokens of ``buf`` (complete lines), and whether it is plain.

    A token starts where a byte above 32 follows a separator (ASCII whitespace or a
    control byte) or the start. Plain: every token is followed by exactly one
    separator, so a token ends one byte before the next one starts.
    """
    word = np.empty(buf.size + 1, dtype=bool)
    word[0] = False
    np.greater(buf, 32, out=word[1:])
    starts = np.flatnonzero(word[1:] > word[:-1])
    return starts, bool(starts.size == buf.size - np.count_nonzero(word))


def tokens_of_lines(chunk: Chunk) -> tuple[I64, I64, I64]:
    """(start, end) offsets of the tokens of a chunk and the first token of each line
    (one more entry: the number of tokens), from :func:`token_starts` (a token ends before
    the next one starts, :func:`token_ends` where separators run on)."""
    buf = chunk.buf
    start, plain = token_starts(buf)
    end = np.empty_like(start)
    np.subtract(start[1:], 1, out=end[:-1])
    end[-1:] = buf.size - 1
    if not plain:
        end = token_ends(buf, end)
    line_start = np.concatenate([[0], chunk.newlines[:-1] + 1])
    return start, end, np.append(np.searchsorted(start, line_start), start.size)


#: Separators walked back at most per token before all separators are looked up.
_WALK = 16


def token_ends(buf: NDArray[np.uint8], end: I64) -> I64:
    """End offsets of tokens, given the separator before the next token (or the last byte).

    Walks back over the rest of a run of separators (CR before LF, double spaces,
    trailing blanks); a long run is looked up among all separators of ``buf`` instead.
    """
    end = end.copy()
    walk = np.flatnonzero(buf[end - 1] <= 32)
    for _ in range(_WALK):
        if not walk.size:
            return end
        end[walk] -= 1
        walk = walk[buf[end[walk] - 1] <= 32]
    if walk.size:
        inside = np.flatnonzero(buf > 32)  # token bytes: the last one before each run
        end[walk] = inside[np.searchsorted(inside, end[walk]) - 1] + 1
    return end


def strided(first: I64, count: I64, offset: int, step: int) -> I64:
    """Token indices ``first + offset, first + offset + step, …`` below ``first + count``."""
    n = np.maximum(count - offset + step - 1, 0) // step
    total = int(n.sum())
    if total == 0:
        return np.zeros(0, dtype=np.int64)
    cum = np.zeros(n.size, dtype=np.int64)
    np.cumsum(n[:-1], out=cum[1:])
    k = np.arange(total, dtype=np.int64) - np.repeat(cum, n)
    return np.repeat(first + offset, n) + step * k


def _fallback(buf, start, end, idx, conv) -> tuple[NDArray, I64]:
    """Convert the tokens ``idx`` with Python (``conv``); return values and the failed ones.

    ``conv`` reads each token's bytes (for bytes as for their ASCII text: a byte above
    127 fails either way). All tokens at once first; one at a time only when one fails.
    """
    data = buf.tobytes()
    texts = [data[a:b] for a, b in zip(start[idx].tolist(), end[idx].tolist())]
    try:
        vals = np.array(list(map(conv, texts)), dtype=np.int64 if conv is int else np.float64)
        return vals, np.zeros(0, dtype=np.int64)
    except (ValueError, OverflowError):  # a token that is no number (or beyond int64)
        pass
    vals, bad = [], []
    for i, text in zip(idx.tolist(), texts):
        try:
            v = conv(text)
            if conv is int and not -(2**63) <= v < 2**63:
                raise ValueError(text)
            vals.append(v)
        except ValueError:
            vals.append(0)
            bad.append(i)
    return np.array(vals), np.array(bad, dtype=np.int64)


def records(buf: NDArray[np.uint8], width: int) -> NDArray:
    """``buf`` seen as overlapping records of ``width`` bytes, one starting at every byte.

    Indexing it with token starts gathers the tokens' bytes in one C loop (much faster
    than indexing a 2-D sliding window).
    """
    return np.ndarray((buf.size - width + 1,), dtype=f"V{width}", buffer=buf, strides=(1,))


def _plain_decimals(
    buf: NDArray[np.uint8], start: I64, width: int, integer: bool
) -> tuple[I64, I64, NDArray]:
    """Tokens of ``width`` bytes, digits and at most one point: (mantissa, decimals, bad).

    The tokens are cut into a (n, width) byte matrix (:func:`records`), the point counts
    as a 0 digit, the digits are summed as int64 by Horner's rule and the point's 0 is
    taken out again. ``bad`` marks tokens with another byte, two
    points or no digit (or a point at all if ``integer``).
    """
    n = start.size
    M = records(buf, width)[start].view(np.uint8).reshape(n, width)  # a copy
    M -= np.uint8(_ZERO)
    isdot = M == np.uint8(_DOT - _ZERO + 256)
    dot_col = isdot.argmax(axis=1)
    has_dot = isdot.ravel()[np.arange(n) * width + dot_col]
    bad = has_dot & (integer or width == 1)
    if width == _MAX_FAST:
        bad |= M[:, 0] == 9  # 19 digits from 9·10¹⁸ on overflow int64
    other = M > 9
    other &= ~isdot
    if other.any():
        bad |= other.any(axis=1)
    if np.count_nonzero(isdot) != np.count_nonzero(has_dot):
        bad |= isdot.sum(axis=1) > 1
    np.putmask(M, isdot, 0)
    total = M[:, 0].astype(np.int64)
    for j in range(1, width):  # Horner's rule over the columns (faster than a product)
        total *= 10
        total += M[:, j]
    frac = np.where(has_dot, width - 1 - dot_col, 0)
    right = total % _POW10[frac]
    mant = np.where(has_dot, right + (total - right) // 10, total)
    return mant, frac, bad


#: A float type whose 64-bit significand holds every mantissa of up to 19 digits, when
#: the platform has one (x86's extended precision; None where long double is a double).
_LONG = np.longdouble if np.finfo(np.longdouble).nmant >= 63 else None
_P10L = 10 ** np.arange(19, dtype=np.int64)


def _wide_quotients(mant: I64, frac: I64) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """mant / 10**frac correctly rounded to doubles for mantissas beyond 2**53, and the
    ones it cannot promise (True: to be read by ``float``).

    In the 64-bit significand the mantissa and 10**frac (frac ≤ 18 < 28) are exact, so
    the quotient q is the exact value rounded once. Every midpoint between two doubles
    has 54 bits and so is a long double: unless q is one, the exact value lies on q's
    side of every midpoint and rounds to the same double as q.
    """
    if _LONG is None:
        return np.zeros(mant.size), np.ones(mant.size, dtype=bool)
    q = mant.astype(_LONG) / _P10L[frac].astype(_LONG)
    d = q.astype(np.float64)
    r = q - d.astype(_LONG)  # exact: below half a double's unit in the last place
    gap = np.nextafter(d, np.where(r > 0, np.inf, -np.inf)) - d
    return d, (r != 0) & (2 * r == gap.astype(_LONG))


def parse_numbers(
    buf: NDArray[np.uint8], start: I64, end: I64, *, integer: bool = False
) -> tuple[NDArray, I64]:
    """Numbers of the tokens ``buf[start:end]``; returns (values, indices of bad tokens).

    Plain decimals ``[+-]digits[.digits]`` of up to 19 bytes are converted vectorised,
    one group of equally long tokens at a time (:func:`_plain_decimals`): the mantissa
    as int64 divided once by a power of ten. Both are exact when the mantissa is at most
    2**53, so the quotient is the correctly rounded value, the double ``float`` reads
    from the token. Other tokens (a longer mantissa, exponents, longer ones, ``nan``)
    are converted by Python; tokens that are not numbers are returned in the second
    array (their value is 0). Integers reject a decimal point.
    """
    n = start.size
    out = np.zeros(n, dtype=np.int64 if integer else np.float64)
    if n == 0:
        return out, np.zeros(0, dtype=np.int64)
    first = buf[start]
    neg = first == _MINUS
    signed = neg | (first == _PLUS)
    digits_at = start + signed
    width = end - digits_at
    slow = (width <= 0) | (end - start > _MAX_FAST)
    width[slow] = 0
    counts = np.bincount(width)
    # the rows of each width in index order: slices of one stable sort of the widths
    # (0 … _MAX_FAST as int8: NumPy's radix sort)
    by_width = np.argsort(width.astype(np.int8), kind="stable")
    ends = np.cumsum(counts).tolist()
    for w in range(1, counts.size):
        if not counts[w]:
            continue
        rows = by_width[ends[w - 1] : ends[w]]
        mant, frac, bad = _plain_decimals(buf, digits_at[rows], w, integer)
        if integer:
            out[rows] = mant
        else:
            out[rows] = mant / _P10F[frac]
            wide = mant > 2**53  # the mantissa not exact as a double
            if wide.any():
                at = np.flatnonzero(wide)
                out[rows[at]], tie = _wide_quotients(mant[at], frac[at])
                bad[at[tie]] = True  # a halfway case (or no wide float here): Python's float
        slow[rows[bad]] = True
    np.negative(out, out=out, where=neg)
    idx = np.flatnonzero(slow)
    bad = np.zeros(0, dtype=np.int64)
    if idx.size:
        vals, bad = _fallback(buf, start, end, idx, int if integer else float)
        out[idx] = vals
    return out, bad
