"""Broken COLMAP text models: one line naming file and line, exit code 2 (library and CLI)."""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.cli import main
from orientviz.io.colmap import write_colmap


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    d = tmp_path_factory.mktemp("colmap")
    write_colmap(ov.simulate_block(1, 3, rng=1).block, d)
    return {
        n: (d / n).read_text().splitlines() for n in ("cameras.txt", "images.txt", "points3D.txt")
    }


def _first_data(lines):
    return next(i for i, s in enumerate(lines) if s and not s.startswith("#"))


def _edit(lines, name, fn):
    """Apply fn(list of lines, index of the first data line) and return (text, line number)."""
    out = list(lines)
    k = fn(out, _first_data(out))
    return "\n".join(out) + "\n", k + 1


def _set(k, text):
    def fn(lines, first):
        lines[first + k] = text(lines[first + k])
        return first + k

    return fn


CASES = {
    # name: (file, edit, words expected in the message)
    "truncated image line": ("images.txt", _set(0, lambda s: " ".join(s.split()[:5])), "fields"),
    "truncated camera line": ("cameras.txt", _set(0, lambda s: " ".join(s.split()[:3])), "fields"),
    "non-number in a point": (
        "points3D.txt",
        _set(1, lambda s: s.replace(s.split()[2], "abc", 1)),
        "number",
    ),
    "non-number in a 2D point": (
        "images.txt",
        _set(1, lambda s: "x1 " + " ".join(s.split()[1:])),
        "number",
    ),
    "unknown camera model": (
        "cameras.txt",
        _set(0, lambda s: s.replace("SIMPLE_PINHOLE", "FISHEYE")),
        "not supported",
    ),
    "dangling camera id": (
        "images.txt",
        _set(2, lambda s: " ".join([*s.split()[:8], "9", *s.split()[9:]])),
        "unknown camera id 9",
    ),
    "dangling POINT3D_ID": (
        "images.txt",
        _set(1, lambda s: " ".join([*s.split()[:2], "99999", *s.split()[3:]])),
        "unknown POINT3D_ID",
    ),
    "dangling TRACK image": (
        "points3D.txt",
        _set(2, lambda s: " ".join([*s.split()[:8], "77", "0"])),
        "IMAGE_ID 77",
    ),
    "wrong parameter count": ("cameras.txt", _set(0, lambda s: s + " 0.5"), "parameters"),
    "2D points not in triplets": ("images.txt", _set(1, lambda s: s + " 5.0"), "triplets"),
    "odd TRACK": ("points3D.txt", _set(0, lambda s: s + " 3"), "pairs"),
    "duplicate point id": (
        "points3D.txt",
        _set(1, lambda s: " ".join(["1", *s.split()[1:]])),
        "duplicate",
    ),
    "duplicate image id": (
        "images.txt",
        _set(2, lambda s: " ".join(["1", *s.split()[1:]])),
        "duplicate",
    ),
    "non-finite quaternion": (
        "images.txt",
        _set(0, lambda s: " ".join([s.split()[0], "inf", *s.split()[2:]])),
        "finite",
    ),
}


@pytest.mark.parametrize("case", list(CASES))
def test_broken_model_names_file_and_line(model, tmp_path, capsys, case):
    name, fn, words = CASES[case]
    files = dict(model)
    text, line = _edit(files[name], name, fn)
    for n, lines in files.items():
        (tmp_path / n).write_text(text if n == name else "\n".join(lines) + "\n")
    with pytest.raises(ov.InputError) as info:
        ov.read_colmap(tmp_path)
    msg = str(info.value)
    assert msg.startswith(str(tmp_path / name)), msg
    assert f"line {line}:" in msg and words in msg, msg
    code = main(["import-colmap", str(tmp_path), "-o", str(tmp_path / "out.json")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and f"{name}: line {line}:" in err, err
    assert not (tmp_path / "out.json").exists()


def test_empty_files_name_a_line(model, tmp_path):
    for n, lines in model.items():
        (tmp_path / n).write_text("\n".join(lines) + "\n")
    (tmp_path / "images.txt").write_text("# nothing\n")
    with pytest.raises(ov.InputError, match=r"images.txt: line 1: no images"):
        ov.read_colmap(tmp_path)


def test_clean_model_reads(model, tmp_path):
    for n, lines in model.items():
        (tmp_path / n).write_text("\n".join(lines) + "\n")
    b = ov.read_colmap(tmp_path)
    assert b.n_images == 3 and np.all(np.isfinite(b.observations.xy))
