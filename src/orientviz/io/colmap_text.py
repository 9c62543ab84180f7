"""COLMAP's text model (cameras.txt, images.txt, points3D.txt) read in one streaming pass.

``images.txt`` holds two lines per image: ``IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID
NAME`` and ``X Y POINT3D_ID`` triplets of *all* its keypoints, most of them unmatched
(``POINT3D_ID = -1``). The file is read once in chunks (:mod:`orientviz.io.colmap_scan`);
the triplets are cut by numpy and only the matched ones are converted to numbers, so
the memory kept is that of the observations, not of the file. Broken input raises one
:class:`~orientviz.errors.InputError` naming the file and line.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError
from .colmap_scan import Chunk, line_chunks, parse_numbers, strided, tokenize

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


def checked_file(path: Path, what: str, *, capped: bool = False) -> Path:
    """:func:`orientviz.io.safeio.check_input_file` (streaming readers are not capped)."""
    from .safeio import check_input_file

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
        if k == "f" and not np.isfinite(v):
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
    seen_lines = 0
    checked_file(path, "a COLMAP text file points3D.txt")
    for chunk in line_chunks(path):
        t = tokenize(chunk.buf)
        first = t.first_of_line()
        count = np.diff(first)
        has = count > 0
        data = has.copy()
        if len(t):
            data &= chunk.buf[t.start[np.where(has, first[:-1], 0)]] != 35  # not a comment
        lines = np.flatnonzero(data)
        seen_lines += lines.size
        short = lines[count[lines] < 8]
        odd = lines[(count[lines] - 8) % 2 == 1]
        for bad, msg in ((short, "expected a 3D point with at least 8 fields"),
                         (odd, "expected TRACK[] as pairs IMAGE_ID POINT2D_IDX")):  # fmt: skip
            if bad.size:
                raise _fail(path, chunk.first_line + int(bad[0]), msg)
        f0 = first[lines]
        pid, badi = parse_numbers(chunk.buf, t.start[f0], t.end[f0], integer=True)
        xyz_tok = (f0[:, None] + np.arange(1, 4)).ravel()
        X, badf = parse_numbers(chunk.buf, t.start[xyz_tok], t.end[xyz_tok])
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
        img, bad = parse_numbers(chunk.buf, t.start[sel], t.end[sel], integer=True)
        if bad.size:
            raise _fail(
                path, chunk.first_line + int(t.line[sel[bad[0]]]), "TRACK: expected integers"
            )
        uniq, at = np.unique(img, return_index=True)
        for u, a in zip(uniq.tolist(), at.tolist()):
            track_first.setdefault(u, chunk.first_line + int(t.line[sel[a]]))
    pid = np.concatenate(ids) if ids else np.zeros(0, np.int64)
    order = np.argsort(pid, kind="stable")
    dup = np.flatnonzero(np.diff(pid[order]) == 0)
    if dup.size:
        lines_of = np.concatenate(where)[order[dup + 1]]
        k = int(np.argmin(lines_of))
        raise _fail(path, int(lines_of[k]), f"duplicate POINT3D_ID {int(pid[order[dup[k]]])}")
    return pid, (np.concatenate(xyz) if xyz else np.zeros((0, 3))), track_first


def read_images_text(path: Path, point_ids: I64, cams: dict[int, ColmapCamera]) -> dict:
    """images.txt: image records and the matched keypoints only (one pass, chunked)."""
    checked_file(path, "a COLMAP text file images.txt")
    lookup = IdIndex(point_ids)
    limit: list[tuple[float, float]] = []  # per image: |u|, |v| limits (px)
    recs: list[tuple] = []
    obs_image, obs_uv, obs_pid = [], [], []
    expect_header = True
    last_header_line = 0
    for chunk in line_chunks(path):
        t = tokenize(chunk.buf)
        first = t.first_of_line()
        count = np.diff(first)
        buf = chunk.buf
        points_lines, points_image = [], []
        for k in range(t.n_lines):  # two lines per image: a Python loop over images only
            start = t.line_start[k]
            is_comment = count[k] > 0 and buf[t.start[first[k]]] == 35
            if is_comment:
                continue
            if expect_header:
                if count[k] == 0:
                    continue  # blank lines between images
                no = chunk.first_line + k
                end = t.end[first[k + 1] - 1]
                f = _text(chunk, int(start), int(end)).split()
                vals = _numbers(path, no, f, "ifffffffi", "an image")
                name = " ".join(f[9:]) if len(f) > 9 else str(vals[0])
                if len(name) > MAX_NAME:
                    raise _fail(
                        path,
                        no,
                        f"image NAME of {len(name)} characters, expected at most {MAX_NAME}",
                    )
                bad = pose_problem(np.array(vals[1:5]), np.array(vals[5:8]))
                if bad:
                    raise _fail(path, no, bad)
                cam = cams.get(vals[8])
                if cam is None:
                    raise _fail(path, no, f"unknown camera id {vals[8]}")
                limit.append((MAX_IMAGE_SIZES * cam.width, MAX_IMAGE_SIZES * cam.height))
                recs.append((vals, name, no))
                last_header_line = no
                expect_header = False
            else:
                points_lines.append(k)
                points_image.append(len(recs) - 1)
                expect_header = True
        if not points_lines:
            continue
        pl = np.array(points_lines, dtype=np.int64)
        bad = pl[count[pl] % 3 != 0]
        if bad.size:
            raise _fail(path, chunk.first_line + int(bad[0]), "expected triplets X Y POINT3D_ID")
        of_line = np.full(t.n_lines + 1, -1, dtype=np.int64)
        of_line[pl] = np.array(points_image, dtype=np.int64)
        pid_tok = strided(first[pl], count[pl], 2, 3)
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
        lim = np.asarray(limit)[of_line[t.line[keep]]]
        far = np.flatnonzero(np.any(np.abs(uv) > lim, axis=1))
        if far.size:
            k = int(far[0])
            raise _fail(path, chunk.first_line + int(t.line[keep[k]]),
                        f"2D point ({uv[k, 0]:g}, {uv[k, 1]:g}) px lies far outside the image")  # fmt: skip
        where_ = lookup.index(pid)
        unknown = np.flatnonzero(where_ < 0)
        if unknown.size:
            at = keep[unknown[0]]
            raise _fail(
                path,
                chunk.first_line + int(t.line[at]),
                f"unknown POINT3D_ID {int(pid[unknown[0]])}",
            )
        obs_image.append(of_line[t.line[keep]])
        obs_uv.append(uv)
        obs_pid.append(where_)  # the index of the point (its POINT3D_ID is point_ids[i])
    if not recs:
        raise _fail(path, max(last_header_line, 1), "no images in the file")
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
        "obs_image": cat(obs_image, (0,)).astype(np.int64),
        "obs_uv": cat(obs_uv, (0, 2)),
        "obs_point": cat(obs_pid, (0,)).astype(np.int64),
    }


def read_text_model(directory: Path) -> ColmapModel:
    """The three text files of ``directory`` as a :class:`ColmapModel` (checked)."""
    cams = read_cameras_text(directory / "cameras.txt")
    pts_path = directory / "points3D.txt"
    pid, xyz, track_first = read_points_text(pts_path)
    img_path = directory / "images.txt"
    im = read_images_text(img_path, pid, cams)
    known = set(im["image_ids"].tolist())
    for iid, line in sorted(track_first.items(), key=lambda kv: kv[1]):
        if iid not in known:
            raise _fail(pts_path, line, f"TRACK names IMAGE_ID {iid}, which is not in images.txt")
    return ColmapModel(
        cams, im["image_ids"], im["names"], im["qvec"], im["tvec"], im["camera"],
        im["obs_image"], im["obs_uv"], im["obs_point"], pid, xyz,
        source={"format": "colmap-text", "images": str(img_path)},
    )  # fmt: skip
