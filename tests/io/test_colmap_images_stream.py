"""images.txt read in chunks, only matched keypoints: the same as a plain line-by-line parse.

The streaming reader (``orientviz.io.colmap_images``) is compared with an independent,
obviously correct parse (``str.split`` and ``float``) of small generated files with the
awkward cases a real file may hold, read with tiny chunks so that every case also falls
on a chunk boundary; and its fast path is compared with its exact path.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from orientviz.errors import InputError
from orientviz.io import colmap_images, colmap_scan
from orientviz.io.colmap_images import read_images_text
from orientviz.io.colmap_text import ColmapCamera

CAMS = {
    1: ColmapCamera("PINHOLE", 4000, 3000, np.array([3000.0, 3001.0, 2000.0, 1500.0])),
    7: ColmapCamera("SIMPLE_PINHOLE", 640, 480, np.array([500.0, 320.0, 240.0])),
}


def simple_parse(text: str, point_ids: np.ndarray) -> dict:
    """images.txt the slow, plain way: lines, ``split``, ``float``, ``int``."""
    where = {int(p): i for i, p in enumerate(point_ids)}
    ids, names, obs_image, obs_uv, obs_point = [], [], [], [], []
    header = True
    for line in text.splitlines():
        fields = line.split()
        if fields and fields[0].startswith("#"):
            continue
        if header:
            if not fields:
                continue
            ids.append(int(fields[0]))
            names.append(" ".join(fields[9:]))
            header = False
            continue
        header = True
        for k in range(0, len(fields), 3):
            if int(fields[k + 2]) != -1:
                obs_image.append(len(ids) - 1)
                obs_uv.append((float(fields[k]), float(fields[k + 1])))
                obs_point.append(where[int(fields[k + 2])])
    return {
        "image_ids": np.array(ids),
        "names": names,
        "obs_image": np.array(obs_image, dtype=np.int64),
        "obs_uv": np.array(obs_uv, dtype=float).reshape(-1, 2),
        "obs_point": np.array(obs_point, dtype=np.int64),
    }


def _coordinate(rng, kind: str) -> str:
    v = rng.uniform(-400.0, 3000.0)
    if kind == "fixed":
        return f"{v:.6f}"
    if kind == "short":
        return f"{v:.2f}".rstrip("0")
    if kind == "integer":
        return str(int(v))
    if kind == "exponent":
        return f"{v:.5e}"
    if kind == "signed":
        return f"{v:+.3f}"
    return f"{v:.15g}"  # up to 15 significant digits: exact through either path


def awkward_model(rng, *, crlf: bool = False) -> tuple[str, np.ndarray]:
    """An images.txt with comments, blank and empty lines, odd spacing, ids out of order."""
    point_ids = rng.permutation(np.arange(1, 400) * 7 + 3)  # sparse, not in order
    kinds = ["fixed", "short", "integer", "exponent", "signed", "general"]
    lines = ["# Image list with two lines of data per image:", "#   IMAGE_ID, ..."]
    image_ids = rng.permutation(np.arange(1, 25) * 5)
    for i, iid in enumerate(image_ids.tolist()):
        cam = 1 if i % 3 else 7
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        head = f"{iid} " + " ".join(repr(float(v)) for v in (*q, *rng.normal(size=3)))
        head += f" {cam} img {i:03d}.jpg"
        if i % 5 == 1:
            lines.append("")  # a blank line between images
        if i % 7 == 2:
            lines.append("   # an indented comment")
        lines.append(head + ("   " if i % 4 == 0 else ""))
        n = [0, 1, 5, 40][i % 4] if i % 6 else 0  # empty POINTS2D lines too
        trip = []
        for _ in range(n):
            pid = int(rng.choice(point_ids)) if rng.random() < 0.4 else -1
            if i % 8 == 3:
                pid = -1  # an image with keypoints but no matched one
            trip.append(f"{_coordinate(rng, rng.choice(kinds))} {_coordinate(rng, 'fixed')} {pid}")
        sep = "\t" if i % 9 == 4 else ("  " if i % 9 == 5 else " ")
        line = sep.join(trip)
        if i % 10 == 6:
            line = "  " + line + "  "  # leading and trailing blanks
        lines.append(line)
    text = ("\r\n" if crlf else "\n").join(lines) + "\n"
    return text, point_ids


def _read(tmp_path: Path, text: str, point_ids, newline: bytes = b"") -> dict:
    path = tmp_path / "images.txt"
    path.write_bytes(text.encode())
    return read_images_text(path, point_ids, CAMS)


def _same(got: dict, want: dict) -> None:
    assert np.array_equal(got["image_ids"], want["image_ids"])
    assert got["names"] == want["names"]
    for key in ("obs_image", "obs_point"):
        assert got[key].dtype == np.int64 and np.array_equal(got[key], want[key]), key
    assert got["obs_uv"].shape == want["obs_uv"].shape
    assert np.array_equal(got["obs_uv"], want["obs_uv"])


@pytest.mark.parametrize("chunk", [None, 64, 257, 4096])
@pytest.mark.parametrize("crlf", [False, True])
def test_streaming_reader_equals_a_plain_parse(tmp_path, monkeypatch, chunk, crlf):
    if chunk:
        monkeypatch.setattr(colmap_scan, "CHUNK_BYTES", chunk)
    for seed in range(3):
        text, pids = awkward_model(np.random.default_rng(seed), crlf=crlf)
        want = simple_parse(text, pids)
        assert want["obs_uv"].size > 0 and (want["obs_uv"] < 0).any()
        _same(_read(tmp_path, text, pids), want)


def test_fast_path_and_exact_path_agree(tmp_path, monkeypatch):
    rng = np.random.default_rng(11)
    text, pids = awkward_model(rng)
    monkeypatch.setattr(colmap_scan, "CHUNK_BYTES", 300)
    taken, fast_path = [], colmap_images._matched_fast

    def counted(*args):
        got = fast_path(*args)
        taken.append(got is not None and got[0].size > 0)
        return got

    monkeypatch.setattr(colmap_images, "_matched_fast", counted)
    fast = _read(tmp_path, text, pids)
    assert sum(taken) > 5  # the fast path did the work in most chunks
    monkeypatch.setattr(colmap_images, "_matched_fast", lambda *a: None)
    _same(fast, _read(tmp_path, text, pids))


def test_long_mantissas_within_one_unit_in_the_last_place(tmp_path):
    rng = np.random.default_rng(5)
    u = rng.uniform(0, 4000, 300)
    trip = " ".join(
        f"{a!r} {b!r} {k + 1}" for k, (a, b) in enumerate(zip(u.tolist(), u[::-1].tolist()))
    )
    text = "1 1 0 0 0 0 0 0 1 a.jpg\n" + trip + "\n"
    got = _read(tmp_path, text, np.arange(1, 301))
    want = np.column_stack([u, u[::-1]])  # repr: 17 significant digits, Python's value
    assert np.all(np.abs(got["obs_uv"] - want) <= np.spacing(want))


def test_a_line_longer_than_the_chunk_and_a_missing_last_newline(tmp_path, monkeypatch):
    monkeypatch.setattr(colmap_scan, "CHUNK_BYTES", 16)
    text = "3 1 0 0 0 0 0 0 7 x.jpg\n" + " ".join(["1.5 2.5 -1"] * 50 + ["10.25 20.5 9"])
    got = _read(tmp_path, text, np.array([9]))
    assert got["obs_uv"].tolist() == [[10.25, 20.5]] and got["obs_point"].tolist() == [0]


@pytest.mark.parametrize(
    "bad, line, words",
    [
        ("1.0 2.0 -2", 4, "-1 (unmatched)"),
        ("1.0 2.0 -10", 4, "-1 (unmatched)"),
        ("1.0 2.0", 4, "triplets"),
        ("1.0 2.0 12.5", 4, "integer POINT3D_ID"),
        ("1.0 nan 8", 4, "finite"),
        ("1.0 2,5 8", 4, "numbers X Y"),
        ("1.0 2.0 99999", 4, "unknown POINT3D_ID 99999"),
        ("1e9 2.0 8", 4, "far outside"),
    ],
)
def test_broken_triplets_name_their_line_after_good_chunks(tmp_path, monkeypatch, bad, line, words):
    monkeypatch.setattr(colmap_scan, "CHUNK_BYTES", 40)
    good = " ".join(["1.5 2.5 -1", "3.5 4.5 8"] * 6)
    text = f"1 1 0 0 0 0 0 0 7 a.jpg\n{good}\n2 1 0 0 0 0 0 0 7 b.jpg\n{good} {bad} {good}\n"
    with pytest.raises(InputError) as info:
        _read(tmp_path, text, np.array([8]))
    msg = str(info.value)
    assert f"images.txt: line {line}:" in msg and words in msg, msg


def test_newlines_are_found_past_the_first_few():
    text = bytearray(b"".join(b"x" * (k % 7) + b"\n" for k in range(1000)))
    buf = np.frombuffer(text, np.uint8)
    for search in (0, 3, 256, 5000):
        got = colmap_scan._newlines(text, buf, search)
        assert np.array_equal(got, np.flatnonzero(buf == 10)), search


@pytest.mark.parametrize("chunk", [None, 50])
def test_points3d_read_like_a_plain_parse(tmp_path, monkeypatch, chunk):
    from orientviz.io.colmap_text import read_points_text

    if chunk:
        monkeypatch.setattr(colmap_scan, "CHUNK_BYTES", chunk)
    rng = np.random.default_rng(3)
    lines, want_ids, want_xyz, first = ["# 3D point list"], [], [], {}
    for k in range(60):
        pid = int(rng.integers(1, 10**6))
        xyz = rng.normal(size=3) * 100
        track = [(int(rng.integers(1, 9)), int(rng.integers(0, 99))) for _ in range(k % 4)]
        sep = ["  ", "\t", " "][k % 3]
        line = sep.join([str(pid), *(f"{v:.6f}" for v in xyz), "1", "2", "3", "0.5"])
        line += "".join(f" {i} {j}" for i, j in track) + (" " if k % 5 == 0 else "")
        lines.append(line + ("\r" if k % 7 == 0 else ""))
        for i, _ in track:
            first.setdefault(i, len(lines))  # the 1-based number of this line
        if k % 11 == 3:
            lines.append("")
        want_ids.append(pid)
        want_xyz.append([float(f"{v:.6f}") for v in xyz])
    path = tmp_path / "points3D.txt"
    path.write_bytes(("\n".join(lines) + "\n").encode())
    ids, xyz, track_first = read_points_text(path)
    assert ids.tolist() == want_ids and np.array_equal(xyz, np.array(want_xyz))
    assert track_first == first
