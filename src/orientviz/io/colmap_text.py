"""COLMAP's text model (cameras.txt, images.txt, points3D.txt) read in one streaming pass.

cameras.txt and points3D.txt are read here (with the model's types and checks that
the other readers share), images.txt by :mod:`orientviz.io.colmap_images` (two lines per
image, ``X Y POINT3D_ID`` triplets of *all* keypoints, most of them unmatched), the three
put together by :func:`orientviz.io.colmap_text_model.read_text_model`: each file once, in chunks
(:mod:`orientviz.io.colmap_scan`), the fields cut by numpy and only the kept ones
converted to numbers, so the memory kept is that of the observations, not of the file.
Broken input raises one :class:`~orientviz.errors.InputError` naming the file and line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError
from .colmap_scan import Chunk, line_chunks, parse_numbers, strided, tokens_of_lines
from .safeio import check_input_file

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: COLMAP camera models: name → (model id, parameter names).
CAMERA_MODELS: dict[str, tuple[int, tuple[str, ...]]] = {
    "SIMPLE_PINHOLE": (0, ("f", "cx", "cy")),
    "PINHOLE": (1, ("fx", "fy", "cx", "cy")),
    "SIMPLE_RADIAL": (2, ("f", "cx", "cy", "k")),
    "RADIAL": (3, ("f", "cx", "cy", "k1", "k2")),
    "OPENCV": (4, ("fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2")),
}
MODEL_BY_ID = {mid: name for name, (mid, _) in CAMERA_MODELS.items()}
#: COLMAP's other models, named in the refusal message.
OTHER_MODELS = {5: "OPENCV_FISHEYE", 6: "FULL_OPENCV", 7: "FOV", 8: "SIMPLE_RADIAL_FISHEYE",
                9: "RADIAL_FISHEYE", 10: "THIN_PRISM_FISHEYE"}  # fmt: skip


#: Coordinates and translations beyond ± this are refused (not adjustable in doubles).
MAX_VALUE: float = 1e15
#: Longest image NAME accepted (characters).
MAX_NAME: int = 256
#: Keypoints farther than this many image sizes outside the image are refused.
MAX_IMAGE_SIZES: float = 100.0
#: TRACK image ids below this are remembered in a table (larger ones are sorted per chunk).
_SEEN_TABLE: int = 1 << 22


def checked_file(path: Path, what: str, *, capped: bool = False) -> Path:
    """:func:`orientviz.io.safeio.check_input_file` (streaming readers are not capped)."""
    return check_input_file(path, what, capped=capped)


def camera_problem(cam: ColmapCamera) -> str | None:
    """Why a camera cannot be used (sizes, focal length, principal point), or None."""
    if not (0 < cam.width < 10**7 and 0 < cam.height < 10**7):
        return f"expected WIDTH and HEIGHT of 1..10^7 pixels, got {cam.width} {cam.height}"
    p = cam.named()
    for name in ("f", "fx", "fy"):
        if name in p and not 0 < p[name] < 1e12:
            return f"expected a focal length {name} > 0 px (below 1e12), got {p[name]:g}"
    for name in ("cx", "cy"):
        if not abs(p[name]) <= 1e12:
            return f"principal point {name} = {p[name]:g} px lies far outside the image"
    if not np.all(np.isfinite(cam.params)):
        return "expected finite parameters"
    return None


def pose_problem(q: F64, t: F64) -> str | None:
    """Why an image pose cannot be used (quaternion not normalised, huge translation)."""
    if not np.all(np.isfinite(t)) or np.max(np.abs(t)) > MAX_VALUE:
        return f"translation beyond ±{MAX_VALUE:g}: not a position"
    if not 0.5 < np.linalg.norm(q) < 2.0:
        return "quaternion is not normalised"
    return None


class IdIndex:
    """Index of integer ids: ``index(q)`` → position of each id in ``ids`` (−1 if unknown).

    A direct lookup table when the ids are dense enough (max id < 8 × count + 2²⁰),
    else a binary search of the sorted ids (queries sorted first, for the cache).
    """

    def __init__(self, ids: I64):
        self.ids = ids
        top = int(ids.max()) if ids.size else -1
        self.table = None
        if ids.size == 0 or (int(ids.min()) >= 0 and top < 8 * ids.size + (1 << 20)):
            self.table = np.full(top + 2, -1, dtype=np.int64)
            self.table[ids] = np.arange(ids.size)
        else:
            self.order = np.argsort(ids, kind="stable")
            self.sorted = ids[self.order]

    def index(self, q: I64) -> I64:
        if self.table is not None:
            ok = (q >= 0) & (q < self.table.size - 1)
            return np.where(ok, self.table[np.where(ok, q, self.table.size - 1)], -1)
        pos = np.minimum(np.searchsorted(self.sorted, q), max(self.sorted.size - 1, 0))
        found = self.sorted[pos] == q if self.sorted.size else np.zeros(q.size, bool)
        return np.where(found, self.order[pos] if self.sorted.size else -1, -1)


@dataclass
class ColmapCamera:
    """One COLMAP camera: model name, image size (px) and parameters (px)."""

    model: str
    width: int
    height: int
    params: F64

    def named(self) -> dict[str, float]:
        return dict(zip(CAMERA_MODELS[self.model][1], map(float, self.params)))


@dataclass
class ColmapModel:
    """The raw tables of a COLMAP model (text or binary), before any conversion."""

    cameras: dict[int, ColmapCamera]
    image_ids: I64
    names: list[str]
    qvec: F64  # (m, 4) qw qx qy qz, world → camera
    tvec: F64  # (m, 3)
    image_camera: I64  # camera id per image
    obs_image: I64  # index into the images
    obs_uv: F64  # (n, 2) px
    obs_point: I64  # index into point_ids
    point_ids: I64
    xyz: F64
    source: dict[str, str] = field(default_factory=dict)


def _fail(path: Path, line: int, msg: str) -> InputError:
    return InputError(msg, source=str(path), where=f"line {line}")


def _text(chunk: Chunk, a: int, b: int) -> str:
    return bytes(chunk.buf[a:b]).decode("utf-8", "replace").strip()


def _numbers(path: Path, line: int, fields: list[str], kinds: str, what: str) -> list:
    if len(fields) < len(kinds):
        raise _fail(path, line, f"expected {what} with {len(kinds)} fields, got {len(fields)}")
    out = []
    for i, (f, k) in enumerate(zip(fields, kinds)):
        try:
            v = int(f) if k == "i" else float(f) if k == "f" else f
        except ValueError:
            kind = "an integer" if k == "i" else "a number"
            raise _fail(
                path, line, f"field {i + 1} of {what}: expected {kind}, got {f!r}"
            ) from None
        if k == "i" and not -(2**63) <= v < 2**63:
            raise _fail(path, line, f"field {i + 1} of {what}: integer {f[:20]}… out of range")
        if k == "f" and not math.isfinite(v):
            raise _fail(path, line, f"field {i + 1} of {what}: expected a finite number, got {f!r}")
        out.append(v)
    return out


def _lines(path: Path):
    """(line number, text) of the non-comment, non-blank lines of a small file."""
    checked_file(path, f"a COLMAP text file {path.name}", capped=True)
    for chunk in line_chunks(path):
        ends = np.flatnonzero(chunk.buf == 10)
        a = 0
        for k, b in enumerate(ends):
            s = _text(chunk, a, int(b))
            a = int(b) + 1
            if s and not s.startswith("#"):
                yield chunk.first_line + k, s


def read_cameras_text(path: Path) -> dict[int, ColmapCamera]:
    """cameras.txt: ``CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]``."""
    cams: dict[int, ColmapCamera] = {}
    last = 1
    for no, line in _lines(path):
        last = no
        f = line.split()
        cid, model, w, h = _numbers(path, no, f, "isii", "a camera")
        if model not in CAMERA_MODELS:
            raise _fail(path, no, f"camera model {model!r} is not supported "
                                  f"(supported: {', '.join(CAMERA_MODELS)})")  # fmt: skip
        names = CAMERA_MODELS[model][1]
        params = _numbers(path, no, f[4:], "f" * len(names), f"{model} parameters")
        if len(f) - 4 != len(names):
            raise _fail(path, no, f"{model} has {len(names)} parameters, got {len(f) - 4}")
        if cid in cams:
            raise _fail(path, no, f"duplicate camera id {cid}")
        cam = ColmapCamera(model, w, h, np.array(params))
        bad = camera_problem(cam)
        if bad:
            raise _fail(path, no, f"camera {cid}: {bad}")
        cams[cid] = cam
    if not cams:
        raise _fail(path, last, "no cameras in the file")
    return cams


def read_points_text(path: Path) -> tuple[I64, F64, dict[int, int]]:
    """points3D.txt: ids, XYZ and, per image id named in a TRACK, the first line naming it."""
    ids, xyz, where, track_first = [], [], [], {}
    seen = np.zeros(0, dtype=bool)  # image ids named in a TRACK so far (small ids)
    seen_lines = 0
    checked_file(path, "a COLMAP text file points3D.txt")
    for chunk in line_chunks(path):
        start, end, first = tokens_of_lines(chunk)
        line_of = lambda tok, first=first: np.searchsorted(first, tok, side="right") - 1  # noqa: E731
        count = np.diff(first)
        has = count > 0
        data = has.copy()
        if start.size:
            data &= chunk.buf[start[np.where(has, first[:-1], 0)]] != 35  # not a comment
        lines = np.flatnonzero(data)
        seen_lines += lines.size
        short = lines[count[lines] < 8]
        odd = lines[(count[lines] - 8) % 2 == 1]
        for bad, msg in ((short, "expected a 3D point with at least 8 fields"),
                         (odd, "expected TRACK[] as pairs IMAGE_ID POINT2D_IDX")):  # fmt: skip
            if bad.size:
                raise _fail(path, chunk.first_line + int(bad[0]), msg)
        f0 = first[lines]
        pid, badi = parse_numbers(chunk.buf, start[f0], end[f0], integer=True)
        xyz_tok = (f0[:, None] + np.arange(1, 4)).ravel()
        X, badf = parse_numbers(chunk.buf, start[xyz_tok], end[xyz_tok])
        for bad, what in ((badi, "POINT3D_ID: expected an integer"),
                          (badf // 3, "X, Y, Z: expected numbers")):  # fmt: skip
            if bad.size:
                raise _fail(path, chunk.first_line + int(lines[bad[0]]), what)
        nonfinite = np.flatnonzero(~np.isfinite(X)) // 3
        if nonfinite.size:
            raise _fail(path, chunk.first_line + int(lines[nonfinite[0]]), "X, Y, Z must be finite")
        huge = np.flatnonzero(np.abs(X) > MAX_VALUE) // 3
        if huge.size:
            raise _fail(path, chunk.first_line + int(lines[huge[0]]),
                        f"a coordinate beyond ±{MAX_VALUE:g}: not a position")  # fmt: skip
        negative = np.flatnonzero(pid < 0)
        if negative.size:
            raise _fail(path, chunk.first_line + int(lines[negative[0]]),
                        f"POINT3D_ID {int(pid[negative[0]])}: expected an id ≥ 0 "
                        "(-1 is COLMAP's 'no 3D point')")  # fmt: skip
        ids.append(pid)
        xyz.append(X.reshape(-1, 3))
        where.append(chunk.first_line + lines)
        sel = strided(f0, count[lines], 8, 2)  # track image ids: tokens 8, 10, 12, …
        img, bad = parse_numbers(chunk.buf, start[sel], end[sel], integer=True)
        if bad.size:
            raise _fail(
                path, chunk.first_line + int(line_of(sel[bad[0]])), "TRACK: expected integers"
            )
        new = np.arange(img.size)
        if img.size and 0 <= img.min() and img.max() < _SEEN_TABLE:  # skip ids seen before
            if img.max() >= seen.size:
                seen = np.concatenate([seen, np.zeros(int(img.max()) + 1 - seen.size, bool)])
            new = np.flatnonzero(~seen[img])
            seen[img] = True
        uniq, at = np.unique(img[new], return_index=True)
        for u, k in zip(uniq.tolist(), line_of(sel[new[at]]).tolist()):
            track_first.setdefault(u, chunk.first_line + k)
    pid = np.concatenate(ids) if ids else np.zeros(0, np.int64)
    order = np.argsort(pid, kind="stable")
    dup = np.flatnonzero(np.diff(pid[order]) == 0)
    if dup.size:
        lines_of = np.concatenate(where)[order[dup + 1]]
        k = int(np.argmin(lines_of))
        raise _fail(path, int(lines_of[k]), f"duplicate POINT3D_ID {int(pid[order[dup[k]]])}")
    return pid, (np.concatenate(xyz) if xyz else np.zeros((0, 3))), track_first
