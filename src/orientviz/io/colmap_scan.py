"""Vectorised scanning of large whitespace-separated text files (COLMAP's text models).

A file is read once, in chunks of whole lines (:func:`line_chunks`); each chunk is cut
into tokens by numpy (:func:`tokenize`: one comparison and one ``flatnonzero`` over the
bytes), and only the tokens a reader keeps are converted to numbers
(:func:`parse_numbers`: digits summed per token as int64, then one division by a power
of ten — the correctly rounded result for up to 15 significant digits, within one unit
in the last place beyond). Tokens in exponent notation or
otherwise unusual fall back to Python's ``float``/``int``. Nothing here knows COLMAP;
:mod:`orientviz.io.colmap_text` builds on it.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import NDArray

#: Bytes read per chunk (a chunk grows to the end of its last line).
CHUNK_BYTES: int = 16 << 20
I64 = NDArray[np.int64]
_POW10 = 10 ** np.arange(19, dtype=np.int64)
_P10F = 10.0 ** np.arange(20)
_ZERO, _DOT, _MINUS, _PLUS = 48, 46, 45, 43


@dataclass
class Chunk:
    """Whole lines of a file: ``buf`` (uint8) and the 1-based number of its first line."""

    buf: NDArray[np.uint8]
    first_line: int


def line_chunks(path: Path, chunk_bytes: int = CHUNK_BYTES) -> Iterator[Chunk]:
    """Read ``path`` once, yielding chunks that end with a newline (one is added at the end)."""
    line = 1
    rest = b""
    with open(path, "rb") as f:
        while True:
            data = f.read(chunk_bytes)
            if not data:
                break
            data = rest + data
            cut = data.rfind(b"\n") + 1
            if cut == 0:  # a line longer than the chunk: keep reading
                rest = data
                continue
            rest = data[cut:]
            buf = np.frombuffer(data, dtype=np.uint8, count=cut)
            yield Chunk(buf, line)
            line += int(np.count_nonzero(buf == 10))
    if rest:
        yield Chunk(np.frombuffer(rest + b"\n", dtype=np.uint8), line)


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
    """Split ``buf`` (complete lines) at ASCII whitespace and control characters."""
    sep = np.flatnonzero(buf <= 32)  # spaces, tabs, CR, LF and other control bytes
    nl = buf[sep] == 10
    line = np.empty(sep.size + 1, dtype=np.int32)  # newlines before each token
    line[0] = 0
    np.cumsum(nl, dtype=np.int32, out=line[1:])
    start = np.empty(sep.size + 1, dtype=np.int64)
    start[0] = 0
    np.add(sep, 1, out=start[1:])
    end = np.empty(sep.size + 1, dtype=np.int64)
    end[:-1] = sep
    end[-1] = buf.size
    n_lines = int(line[-1])
    keep = end > start
    if not keep.all():  # runs of separators leave empty tokens
        start, end, line = start[keep], end[keep], line[keep]
    line_start = np.concatenate([[0], sep[nl] + 1])[:-1]
    return Tokens(start, end, line, line_start, n_lines)


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
    """Convert the tokens ``idx`` with Python (``conv``); return values and the failed ones."""
    vals, bad = [], []
    for i in idx:
        text = bytes(buf[start[i] : end[i]]).decode("ascii", "replace")
        try:
            v = conv(text)
            if conv is int and not -(2**63) <= v < 2**63:
                raise ValueError(text)
            vals.append(v)
        except ValueError:
            vals.append(0)
            bad.append(i)
    return np.array(vals), np.array(bad, dtype=np.int64)


def parse_numbers(
    buf: NDArray[np.uint8], start: I64, end: I64, *, integer: bool = False
) -> tuple[NDArray, I64]:
    """Numbers of the tokens ``buf[start:end]``; returns (values, indices of bad tokens).

    Plain decimals ``[+-]digits[.digits]`` of up to 18 digits are converted vectorised:
    the tokens are viewed right-aligned in a (n, W) byte matrix (a sliding window ending
    at each token's end), their digits summed by Horner's rule as int64 (the decimal
    point counted as a 0 digit and removed afterwards) and divided once by a power of
    ten. Other tokens (exponents, longer ones, ``nan``) are converted by Python; tokens
    that are not numbers are returned in the second array (their value is 0).
    Integers reject a decimal point.
    """
    n = start.size
    out = np.zeros(n, dtype=np.int64 if integer else np.float64)
    if n == 0:
        return out, np.zeros(0, dtype=np.int64)
    lens = end - start
    W = int(min(lens.max(), 19))
    lead = max(0, W - int(end.min()))
    src = np.concatenate([np.full(lead, 32, np.uint8), buf]) if lead else buf
    M = sliding_window_view(src, W)[np.minimum(end, start + W) + lead - W]  # a copy
    M[np.arange(W) < (W - np.minimum(lens, W))[:, None]] = _ZERO  # left padding: zeros
    first = buf[start]
    neg = first == _MINUS
    signed = neg | (first == _PLUS)
    rows = np.flatnonzero(signed & (lens <= W))
    M[rows, W - lens[rows]] = _ZERO
    d = M - np.uint8(_ZERO)
    isdot = d == np.uint8(_DOT - _ZERO + 256)
    n_dots = isdot.sum(axis=1)
    slow = (
        ((d > 9) & ~isdot).any(axis=1) | (n_dots > 1) | (lens > W) | (lens - n_dots - signed == 0)
    )
    if integer:
        slow |= n_dots > 0
    d[isdot] = 0
    total = np.zeros(n, dtype=np.int64)
    for j in range(W):  # Horner's rule over the W columns
        total *= 10
        total += d[:, j]
    frac = np.where(n_dots > 0, W - 1 - isdot.argmax(axis=1), 0)
    right = total % _POW10[frac]
    mant = np.where(n_dots > 0, right + (total - right) // 10, total)
    if integer:
        out[:] = np.where(neg, -mant, mant)
    else:
        val = mant / _P10F[frac]
        out[:] = np.where(neg, -val, val)
    idx = np.flatnonzero(slow)
    bad = np.zeros(0, dtype=np.int64)
    if idx.size:
        vals, bad = _fallback(buf, start, end, idx, int if integer else float)
        out[idx] = vals
    return out, bad
