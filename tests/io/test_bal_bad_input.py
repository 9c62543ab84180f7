"""Broken BAL files: one line naming file and line, exit code 2 (library and CLI)."""

from __future__ import annotations

import pytest

from orientviz.cli import main
from orientviz.errors import InputError
from orientviz.io.bal import read_bal

CAM = ["3.14", "0", "0", "0", "0", "1500", "15200", "0", "0"]  # one number per line
GOOD = ["1 2 2", "0 0 1.0 2.0", "0 1 -3.0 4.0", *CAM, "1", "2", "3", "4", "5", "6"]


def _with(k, text):
    lines = list(GOOD)
    lines[k] = text
    return lines


CASES = {
    # name: (lines of the file, line number expected, words expected)
    "header not numbers": (_with(0, "1 2 x"), 1, "header"),
    "header too short": (_with(0, "1 2"), 1, "header"),
    "negative count": (_with(0, "1 -2 2"), 1, "non-negative"),
    "truncated observation": (_with(2, "0 1 -3.0"), 3, "4 values"),
    "non-number observation": (_with(1, "0 0 1.0 abc"), 2, "number"),
    "dangling camera index": (_with(2, "3 1 -3.0 4.0"), 3, "camera index"),
    "dangling point index": (_with(1, "0 7 1.0 2.0"), 2, "point index"),
    "fractional index": (_with(1, "0 0.5 1.0 2.0"), 2, "point index"),
    "non-number camera parameter": (_with(5, "one"), 6, "number"),
    "non-finite camera parameter": (_with(5, "nan"), 6, "finite"),
    "non-positive focal length": (_with(9, "0"), 10, "focal length"),
    "non-finite point": (_with(14, "inf"), 15, "finite"),
    "file ends early": (GOOD[:-2], 16, "ends"),
    "extra numbers": ([*GOOD, "7"], 19, "more"),
    "fewer observation lines": (["1 2 5", *GOOD[1:3]], 3, "observation lines"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_broken_bal_names_file_and_line(tmp_path, capsys, case):
    lines, line, words = CASES[case]
    path = tmp_path / "broken.bal"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError) as info:
        read_bal(path)
    msg = str(info.value)
    assert msg.startswith(f"{path}: line {line}:") and words in msg, msg
    code = main(["import-bal", str(path), "-o", str(tmp_path / "out.json")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and f"broken.bal: line {line}:" in err, err
    assert not (tmp_path / "out.json").exists()


def test_good_file_reads(tmp_path):
    path = tmp_path / "good.bal"
    path.write_text("\n".join(GOOD) + "\n")
    b = read_bal(path)
    assert (b.n_images, b.n_points, b.n_observations) == (1, 2, 2)
