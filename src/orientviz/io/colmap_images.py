"""images.txt of a COLMAP text model: the image records and only the matched keypoints.

``images.txt`` holds two lines per image: ``IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID
NAME`` and the ``X Y POINT3D_ID`` triplets of *all* its keypoints, most of them
unmatched (``POINT3D_ID = -1``). The file is read once, in chunks of whole lines
(:func:`~orientviz.io.colmap_scan.line_chunks`). In a chunk:

1. the token starts are found by one comparison of neighbouring bytes
   (:func:`~orientviz.io.colmap_scan.token_starts`); the lines (and which of them are
   image records, which POINTS2D) by the newlines, a Python loop over lines only;
2. a POINTS2D line's triplets are its consecutive token triples, so every POINT3D_ID is
   judged by its first two bytes (``-1`` followed by a separator = unmatched), without
   splitting or converting the unmatched keypoints;
3. only the matched triplets' X, Y and POINT3D_ID are converted to numbers, vectorised
   (:func:`~orientviz.io.colmap_scan.parse_numbers`).

Whatever this fast path does not accept (a field that is not a plain number, a wrong
count, an unknown id, a keypoint far outside the image, …) makes the chunk be read
again by the exact path, which checks every token as well and either raises one
:class:`~orientviz.errors.InputError` naming the file and line or gives the same
arrays.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from .colmap_scan import (
    Chunk,
    line_chunks,
    parse_numbers,
    strided,
    token_ends,
    token_starts,
    tokenize,
)
from .colmap_text import (
    MAX_IMAGE_SIZES,
    MAX_NAME,
    MAX_VALUE,
    ColmapCamera,
    IdIndex,
    _fail,
    _numbers,
    checked_file,
    pose_problem,
)

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]
#: Bytes a line's end is stripped of (ASCII whitespace and control characters).
_SEPARATORS = bytes(range(33))
_UNMATCHED = 0x312D  # the bytes "-1" read as one little-endian uint16


class _Images:
    """What the image records of the file said so far (the state between chunks)."""

    def __init__(self, path: Path, cams: dict[int, ColmapCamera]):
        self.path = path
        self.cams = cams
        self.recs: list[tuple[list, str, int]] = []  # (fields, NAME, line number)
        self.limit = np.zeros((64, 2))  # per image: |u|, |v| limits (px), grown by doubling
        self.expect_header = True

    def header(self, chunk: Chunk, a: int, b: int, no: int) -> None:
        """Check and keep the image record in ``chunk.buf[a:b]`` (line ``no``)."""
        path = self.path
        text = bytes(chunk.buf[a:b]).rstrip(_SEPARATORS).decode("utf-8", "replace").strip()
        f = text.split()
        vals = _numbers(path, no, f, "ifffffffi", "an image")
        name = " ".join(f[9:]) if len(f) > 9 else str(vals[0])
        if len(name) > MAX_NAME:
            raise _fail(path, no, f"image NAME of {len(name)} characters, expected at most {MAX_NAME}")  # fmt: skip
        q, t = vals[1:5], vals[5:8]
        if not (max(map(abs, t)) <= MAX_VALUE and 0.5 < math.sqrt(sum(x * x for x in q)) < 2.0):
            bad = pose_problem(np.array(q), np.array(t))  # the message (vals are finite)
            if bad:
                raise _fail(path, no, bad)
        cam = self.cams.get(vals[8])
        if cam is None:
            raise _fail(path, no, f"unknown camera id {vals[8]}")
        k = len(self.recs)
        if k == len(self.limit):
            self.limit = np.concatenate([self.limit, np.zeros_like(self.limit)])
        self.limit[k] = MAX_IMAGE_SIZES * cam.width, MAX_IMAGE_SIZES * cam.height
        self.recs.append((vals, name, no))
        self.expect_header = False

    def lines(self, chunk: Chunk, starts: I64) -> tuple[I64, I64, I64]:
        """The chunk's POINTS2D lines: (chunk-local line index, image index), and the
        index of each line's first token (one more entry: the number of tokens)."""
        buf = chunk.buf
        nl = chunk.newlines
        line_start = np.concatenate([[0], nl[:-1] + 1])
        first = np.append(np.searchsorted(starts, line_start), starts.size)
        count = np.diff(first)
        opens = buf[starts[np.minimum(first[:-1], max(starts.size - 1, 0))]] if starts.size else []
        points, image = [], []
        for k in range(nl.size):  # two lines per image: a Python loop over images only
            if count[k] > 0 and opens[k] == 35:
                continue  # a comment
            if self.expect_header:
                if count[k] > 0:  # blank lines between images are skipped
                    self.header(chunk, int(line_start[k]), int(nl[k]), chunk.first_line + k)
            else:
                points.append(k)
                image.append(len(self.recs) - 1)
                self.expect_header = True
        return np.array(points, dtype=np.int64), np.array(image, dtype=np.int64), first


def _first_bytes(buf: NDArray[np.uint8], at: I64) -> NDArray[np.uint32]:
    """The four bytes from each offset ``at`` (ascending) as little-endian uint32 (newlines
    beyond the end)."""
    words = np.ndarray((buf.size - 3,), dtype="<u4", buffer=buf, strides=(1,))
    out = words[np.minimum(at, buf.size - 4)]
    for k in range(int(np.searchsorted(at, buf.size - 3)), at.size):
        out[k] = int.from_bytes((bytes(buf[at[k] : at[k] + 4]) + b"\n\n\n")[:4], "little")
    return out


def _matched_fast(chunk, starts, plain, first, lines, image, limit, lookup):
    """(image index, uv, point index) of the matched triplets, or None: read exactly."""
    buf = chunk.buf
    f0 = first[lines]
    count = first[lines + 1] - f0
    if np.any(count % 3):
        return None
    at = [starts[a + 2 : a + c : 3] for a, c in zip(f0.tolist(), count.tolist())]
    id_at = np.concatenate(at) if at else np.zeros(0, np.int64)  # each POINT3D_ID's start
    if id_at.size == 0:
        return np.zeros(0, np.int64), np.zeros((0, 2)), np.zeros(0, np.int64)
    w = _first_bytes(buf, id_at)
    unmatched = (w & 0xFFFF) == _UNMATCHED
    if np.count_nonzero((w & 0xFF) == 45) != np.count_nonzero(unmatched):
        return None  # a negative id other than -1
    if np.any(unmatched & ((w & 0xFFFFFF) > _UNMATCHED + (32 << 16))):
        return None  # "-1…" longer than -1
    keep = np.flatnonzero((w & 0xFF) != 45)
    triplets = np.cumsum(count // 3)
    line = np.searchsorted(triplets, keep, side="right")
    tok = f0[line] + 3 * (keep - (triplets[line] - count[line] // 3)) + 2  # token of the id
    n = keep.size
    tok = np.concatenate([np.column_stack([tok - 2, tok - 1]).ravel(), tok])  # X Y X Y …, ids
    begin = starts[tok]
    nxt = tok + 1
    end = np.where(nxt < starts.size, starts[np.minimum(nxt, starts.size - 1)] - 1, buf.size - 1)
    if not plain:
        end = token_ends(buf, end)
    uv, bad_f = parse_numbers(buf, begin[: 2 * n], end[: 2 * n])
    pid, bad_i = parse_numbers(buf, begin[2 * n :], end[2 * n :], integer=True)
    if bad_f.size or bad_i.size or not np.all(np.isfinite(uv)):
        return None
    uv = uv.reshape(n, 2)
    img = image[line]
    if np.any(np.abs(uv) > limit[img]):
        return None
    point = lookup.index(pid)
    if np.any(point < 0):
        return None
    return img, uv, point


def _matched_exact(path, chunk, lines, image, limit, lookup):
    """The matched triplets of ``lines``, every token checked; raises on broken input."""
    t = tokenize(chunk.buf)
    first = t.first_of_line()
    count = np.diff(first)
    buf = chunk.buf
    bad = lines[count[lines] % 3 != 0]
    if bad.size:
        raise _fail(path, chunk.first_line + int(bad[0]), "expected triplets X Y POINT3D_ID")
    of_line = np.full(t.n_lines + 1, -1, dtype=np.int64)
    of_line[lines] = image
    pid_tok = strided(first[lines], count[lines], 2, 3)
    minus = buf[t.start[pid_tok]] == 45
    unmatched = pid_tok[minus]
    odd = unmatched[
        (t.end[unmatched] - t.start[unmatched] != 2) | (buf[t.start[unmatched] + 1] != 49)
    ]
    if odd.size:
        raise _fail(path, chunk.first_line + int(t.line[odd[0]]),
                    "POINT3D_ID must be -1 (unmatched) or a point id ≥ 0")  # fmt: skip
    keep = pid_tok[~minus]
    pid, badi = parse_numbers(buf, t.start[keep], t.end[keep], integer=True)
    uv_tok = np.column_stack([keep - 2, keep - 1]).ravel()
    uv, badf = parse_numbers(buf, t.start[uv_tok], t.end[uv_tok])
    for bad_tok in (keep[badi], uv_tok[badf]):
        if bad_tok.size:
            raise _fail(path, chunk.first_line + int(t.line[bad_tok[0]]),
                        "expected numbers X Y and an integer POINT3D_ID")  # fmt: skip
    if not np.all(np.isfinite(uv)):
        at = uv_tok[np.flatnonzero(~np.isfinite(uv))[0]]
        raise _fail(path, chunk.first_line + int(t.line[at]), "X, Y must be finite")
    uv = uv.reshape(-1, 2)
    img = of_line[t.line[keep]]
    far = np.flatnonzero(np.any(np.abs(uv) > limit[img], axis=1))
    if far.size:
        k = int(far[0])
        raise _fail(path, chunk.first_line + int(t.line[keep[k]]),
                    f"2D point ({uv[k, 0]:g}, {uv[k, 1]:g}) px lies far outside the image")  # fmt: skip
    point = lookup.index(pid)
    unknown = np.flatnonzero(point < 0)
    if unknown.size:
        raise _fail(path, chunk.first_line + int(t.line[keep[unknown[0]]]),
                    f"unknown POINT3D_ID {int(pid[unknown[0]])}")  # fmt: skip
    return img, uv, point


def read_images_text(path: Path, point_ids: I64, cams: dict[int, ColmapCamera]) -> dict:
    """images.txt: image records and the matched keypoints only (one pass, chunked).

    Returns a dict of ``image_ids``, ``qvec`` (m, 4), ``tvec`` (m, 3), ``camera``,
    ``names``, ``lines`` (line of each record) and per matched keypoint ``obs_image``
    (index of the image), ``obs_uv`` (n, 2) px and ``obs_point`` (index into
    ``point_ids``).
    """
    checked_file(path, "a COLMAP text file images.txt")
    lookup = IdIndex(point_ids)
    state = _Images(path, cams)
    obs_image, obs_uv, obs_pid = [], [], []
    for chunk in line_chunks(path):
        starts, plain = token_starts(chunk.buf)
        lines, image, first = state.lines(chunk, starts)
        if not lines.size:
            continue
        limit = state.limit[: len(state.recs)]
        got = _matched_fast(chunk, starts, plain, first, lines, image, limit, lookup)
        if got is None:
            got = _matched_exact(path, chunk, lines, image, limit, lookup)
        obs_image.append(got[0])
        obs_uv.append(got[1])
        obs_pid.append(got[2])  # the index of the point (its POINT3D_ID is point_ids[i])
    recs = state.recs
    if not recs:
        raise _fail(path, 1, "no images in the file")
    vals = np.array([r[0][:8] for r in recs], dtype=float)
    ids = np.array([r[0][0] for r in recs], dtype=np.int64)
    order = np.sort(ids)
    dup = np.flatnonzero(np.diff(order) == 0)
    if dup.size:
        again = [r for r in recs if r[0][0] == order[dup[0]]][1]
        raise _fail(path, again[2], f"duplicate IMAGE_ID {int(order[dup[0]])}")
    cat = lambda a, shape: np.concatenate(a) if a else np.zeros(shape)  # noqa: E731
    return {
        "image_ids": ids,
        "qvec": vals[:, 1:5],
        "tvec": vals[:, 5:8],
        "camera": np.array([r[0][8] for r in recs], dtype=np.int64),
        "names": [r[1] for r in recs],
        "lines": [r[2] for r in recs],
        "obs_image": cat(obs_image, (0,)).astype(np.int64, copy=False),
        "obs_uv": cat(obs_uv, (0, 2)),
        "obs_point": cat(obs_pid, (0,)).astype(np.int64, copy=False),
    }
