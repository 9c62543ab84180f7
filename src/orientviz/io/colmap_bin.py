"""COLMAP's binary model (cameras.bin, images.bin, points3D.bin), read without copying.

Layout (little-endian, as COLMAP writes it):

* cameras.bin: ``uint64 n``; per camera ``int32 CAMERA_ID, int32 MODEL_ID, uint64
  WIDTH, uint64 HEIGHT, float64 PARAMS[k]`` (k by the model).
* images.bin: ``uint64 n``; per image ``uint32 IMAGE_ID, float64 QW QX QY QZ, float64
  TX TY TZ, uint32 CAMERA_ID, NAME (bytes, NUL-terminated), uint64 N2D``, then N2D
  records ``float64 X, float64 Y, int64 POINT3D_ID`` (−1 = unmatched).
* points3D.bin: ``uint64 n``; per point ``uint64 POINT3D_ID, float64 X Y Z, uint8 R G B,
  float64 ERROR, uint64 TRACK_LENGTH``, then TRACK_LENGTH pairs ``uint32 IMAGE_ID,
  uint32 POINT2D_IDX``.

The files are memory-mapped; the keypoint records of an image are viewed as one numpy
array and only the matched ones are copied. A truncated or inconsistent file raises one
:class:`~orientviz.errors.InputError` naming the file and the byte offset.
"""

from __future__ import annotations

import mmap
import struct
from pathlib import Path

import numpy as np

from ..errors import InputError
from .colmap_text import (
    CAMERA_MODELS,
    MAX_IMAGE_SIZES,
    MAX_NAME,
    MAX_VALUE,
    MODEL_BY_ID,
    OTHER_MODELS,
    ColmapCamera,
    ColmapModel,
    IdIndex,
    camera_problem,
    checked_file,
    pose_problem,
)

KEYPOINT = np.dtype([("x", "<f8"), ("y", "<f8"), ("id", "<i8")])
TRACK = np.dtype([("image", "<u4"), ("idx", "<u4")])


class _Reader:
    """Sequential reads from a memory map, failing with the file and the byte offset."""

    def __init__(self, path: Path):
        self.path = path
        checked_file(path, f"a COLMAP binary file {path.name}")
        try:
            with open(path, "rb") as f:
                size = f.seek(0, 2)
                self.buf = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) if size else b""
        except FileNotFoundError:
            raise InputError("file not found", source=str(path)) from None
        self.pos = 0

    def fail(self, msg: str, at: int | None = None) -> InputError:
        return InputError(
            msg, source=str(self.path), where=f"byte {self.pos if at is None else at}"
        )

    def take(self, fmt: str, what: str) -> tuple:
        n = struct.calcsize(fmt)
        if self.pos + n > len(self.buf):
            raise self.fail(f"file ends inside {what} (truncated)")
        out = struct.unpack_from(fmt, self.buf, self.pos)
        self.pos += n
        return out

    def count(self, what: str, min_record: int) -> int:
        """The record count at the start of the file, at most what the bytes can hold."""
        (n,) = self.take("<Q", f"the number of {what}")
        most = (len(self.buf) - self.pos) // min_record
        if n > most:
            raise self.fail(f"announces {n} {what}, the file holds at most {most}", 0)
        return n

    def array(self, dtype: np.dtype, count: int, what: str) -> np.ndarray:
        n = dtype.itemsize * count
        if count < 0 or self.pos + n > len(self.buf):
            raise self.fail(f"file ends inside {what} ({count} records announced, truncated)")
        out = np.frombuffer(self.buf, dtype=dtype, count=count, offset=self.pos)
        self.pos += n
        return out

    def name(self) -> str:
        end = self.buf.find(b"\0", self.pos)
        if end < 0:
            raise self.fail("image NAME is not terminated (truncated)")
        text = bytes(self.buf[self.pos : end]).decode("utf-8", "replace")
        self.pos = end + 1
        return text

    def done(self) -> None:
        if self.pos != len(self.buf):
            raise self.fail(f"{len(self.buf) - self.pos} bytes after the last record")


def read_cameras_bin(path: Path) -> dict[int, ColmapCamera]:
    r = _Reader(path)
    n = r.count("cameras", 24)
    cams: dict[int, ColmapCamera] = {}
    for _ in range(n):
        at = r.pos
        cid, mid, w, h = r.take("<iiQQ", "a camera")
        if mid not in MODEL_BY_ID:
            name = OTHER_MODELS.get(mid, f"id {mid}")
            raise r.fail(f"camera model {name} is not supported "
                         f"(supported: {', '.join(CAMERA_MODELS)})", at)  # fmt: skip
        model = MODEL_BY_ID[mid]
        k = len(CAMERA_MODELS[model][1])
        params = np.array(r.take(f"<{k}d", f"the {model} parameters"))
        if cid in cams:
            raise r.fail(f"duplicate camera id {cid}", at)
        cam = ColmapCamera(model, int(w), int(h), params)
        bad = camera_problem(cam)
        if bad:
            raise r.fail(f"camera {cid}: {bad}", at)
        cams[cid] = cam
    r.done()
    if not cams:
        raise r.fail("no cameras in the file")
    return cams


def read_points_bin(path: Path) -> tuple[np.ndarray, np.ndarray, set[int]]:
    r = _Reader(path)
    n = r.count("points", 51)
    head = 51  # uint64 id, 3 float64, 3 uint8, float64 error, uint64 track length
    buf, size = r.buf, len(r.buf)
    starts = [0] * n
    lengths = [0] * n
    pos = r.pos
    from_bytes = int.from_bytes
    for k in range(n):  # only the record lengths; the fields are gathered below
        if pos + head > size:
            r.pos = pos
            raise r.fail("file ends inside a 3D point (truncated)")
        length = from_bytes(buf[pos + 43 : pos + 51], "little")
        starts[k], lengths[k] = pos, length
        pos += head + TRACK.itemsize * length
        if pos > size:
            raise r.fail("file ends inside a TRACK (truncated)", starts[k])
    r.pos = pos
    r.done()
    raw = np.frombuffer(buf, dtype=np.uint8) if size else np.zeros(0, np.uint8)
    at0 = np.array(starts, dtype=np.int64)
    ids = raw[at0[:, None] + np.arange(8)].copy().view("<u8").ravel().astype(np.int64)
    xyz = raw[at0[:, None] + 8 + np.arange(24)].copy().view("<f8").reshape(-1, 3)
    offs = at0 + head
    lens = np.array(lengths, dtype=np.int64)
    at = np.repeat(offs, lens) + TRACK.itemsize * (
        np.arange(int(lens.sum())) - np.repeat(np.cumsum(lens) - lens, lens)
    )
    image = raw[at[:, None] + np.arange(4)].copy().view("<u4").ravel()
    track_images = set(np.unique(image).tolist())
    bad = np.flatnonzero(~np.all(np.isfinite(xyz) & (np.abs(xyz) <= MAX_VALUE), axis=1))
    if bad.size:
        raise r.fail(f"3D point {int(ids[bad[0]])}: X, Y, Z must be finite and within "
                     f"±{MAX_VALUE:g}", int(offs[bad[0]]) - 43)  # fmt: skip
    s = np.sort(ids)
    dup = np.flatnonzero(np.diff(s) == 0)
    if dup.size:
        raise InputError(f"duplicate POINT3D_ID {int(s[dup[0]])}", source=str(path))
    return ids, xyz, track_images


def read_images_bin(path: Path, point_ids: np.ndarray, cams: dict[int, ColmapCamera]) -> dict:
    r = _Reader(path)
    n = r.count("images", 73)
    ids = np.empty(n, dtype=np.int64)
    pose = np.empty((n, 7))
    cam = np.empty(n, dtype=np.int64)
    names: list[str] = []
    obs_image, obs_uv, obs_pid = [], [], []
    lookup = IdIndex(point_ids)
    for k in range(n):
        at = r.pos
        vals = r.take("<I7dI", "an image")
        ids[k], pose[k], cam[k] = vals[0], vals[1:8], vals[8]
        names.append(r.name())
        if len(names[-1]) > MAX_NAME:
            raise r.fail(
                f"image {vals[0]}: NAME of {len(names[-1])} characters, expected at most {MAX_NAME}",
                at,
            )
        bad = pose_problem(np.array(vals[1:5]), np.array(vals[5:8]))
        if bad:
            raise r.fail(f"image {vals[0]}: {bad}", at)
        if vals[8] not in cams:
            raise r.fail(f"image {vals[0]}: unknown camera id {vals[8]}", at)
        lim = MAX_IMAGE_SIZES * np.array([cams[vals[8]].width, cams[vals[8]].height])
        (m,) = r.take("<Q", "the number of keypoints")
        kp = r.array(KEYPOINT, m, "the keypoints")
        keep = kp[kp["id"] != -1]
        if np.any(keep["id"] < 0):
            raise r.fail(f"image {vals[0]}: POINT3D_ID must be -1 or ≥ 0", at)
        pid = keep["id"].astype(np.int64)
        index = lookup.index(pid)
        if np.any(index < 0):
            raise r.fail(
                f"image {vals[0]}: unknown POINT3D_ID {int(pid[np.argmax(index < 0)])}", at
            )
        uv = np.column_stack([keep["x"], keep["y"]])
        if not np.all(np.isfinite(uv) & (np.abs(uv) <= lim)):
            raise r.fail(f"image {vals[0]}: keypoints must be finite and near the image", at)
        obs_image.append(np.full(pid.size, k, dtype=np.int64))
        obs_uv.append(uv)
        obs_pid.append(index)  # the index of the point (its POINT3D_ID is point_ids[i])
    r.done()
    if n == 0:
        raise r.fail("no images in the file")
    s = np.sort(ids)
    dup = np.flatnonzero(np.diff(s) == 0)
    if dup.size:
        raise InputError(f"duplicate IMAGE_ID {int(s[dup[0]])}", source=str(path))
    return {
        "image_ids": ids, "qvec": pose[:, :4], "tvec": pose[:, 4:], "camera": cam,
        "names": names, "obs_image": np.concatenate(obs_image),
        "obs_uv": np.concatenate(obs_uv).reshape(-1, 2), "obs_point": np.concatenate(obs_pid),
    }  # fmt: skip


def read_binary_model(directory: Path) -> ColmapModel:
    """The three binary files of ``directory`` as a :class:`ColmapModel` (checked)."""
    cams = read_cameras_bin(directory / "cameras.bin")
    pid, xyz, track_images = read_points_bin(directory / "points3D.bin")
    img_path = directory / "images.bin"
    im = read_images_bin(img_path, pid, cams)
    dangling = sorted(track_images - set(im["image_ids"].tolist()))
    if dangling:
        raise InputError(f"TRACK names IMAGE_ID {dangling[0]}, which is not in images.bin",
                         source=str(directory / "points3D.bin"))  # fmt: skip
    return ColmapModel(
        cams, im["image_ids"], im["names"], im["qvec"], im["tvec"], im["camera"],
        im["obs_image"], im["obs_uv"], im["obs_point"], pid, xyz,
        source={"format": "colmap-binary", "images": str(img_path)},
    )  # fmt: skip


def write_binary_model(model: ColmapModel, directory: Path) -> None:
    """Write ``model`` in COLMAP's binary layout (tests, benchmarks); keypoints = observations."""
    directory.mkdir(parents=True, exist_ok=True)
    out = [struct.pack("<Q", len(model.cameras))]
    for cid, c in sorted(model.cameras.items()):
        out.append(struct.pack("<iiQQ", cid, CAMERA_MODELS[c.model][0], c.width, c.height))
        out.append(np.asarray(c.params, "<f8").tobytes())
    (directory / "cameras.bin").write_bytes(b"".join(out))
    out = [struct.pack("<Q", model.image_ids.size)]
    tracks: dict[int, list[tuple[int, int]]] = {}
    for k, iid in enumerate(model.image_ids.tolist()):
        sel = np.flatnonzero(model.obs_image == k)
        out.append(
            struct.pack("<I7dI", iid, *model.qvec[k], *model.tvec[k], int(model.image_camera[k]))
        )
        out.append(model.names[k].encode() + b"\0" + struct.pack("<Q", sel.size))
        kp = np.zeros(sel.size, KEYPOINT)
        pids = model.point_ids[model.obs_point[sel]]
        kp["x"], kp["y"], kp["id"] = model.obs_uv[sel, 0], model.obs_uv[sel, 1], pids
        out.append(kp.tobytes())
        for j, p in enumerate(pids.tolist()):
            tracks.setdefault(p, []).append((iid, j))
    (directory / "images.bin").write_bytes(b"".join(out))
    out = [struct.pack("<Q", model.point_ids.size)]
    for pid, X in zip(model.point_ids.tolist(), model.xyz):
        tr = tracks.get(pid, [])
        out.append(struct.pack("<Q3d3BdQ", pid, *X, 128, 128, 128, 0.0, len(tr)))
        out.append(np.array(tr, dtype=TRACK).tobytes() if tr else b"")
    (directory / "points3D.bin").write_bytes(b"".join(out))
