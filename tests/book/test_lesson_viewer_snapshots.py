"""Every live viewer of a lesson has its static picture for the offline book.

A lesson cell ``show_live(..., snapshot="NAME")`` shows the viser viewer live in
JupyterLab; the book (no kernel, no server) shows ``book/_static/lesson_viewer/NAME.png`` in its
place (book/_ext/orientviz_book.py), written by ``tools/make_lesson_snapshots.py``. This
test finds every such call in the lessons and checks its picture: present, small, and not
blank. (That the picture is what the lesson's scene looks like is the tool's job: it
photographs the scene the lesson itself built.)
"""

from __future__ import annotations

import json
import pathlib
import re
import sys

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).parents[2]
CALL = re.compile(r"show_live\((?:[^()]|\([^()]*\))*?snapshot=\"([^\"]+)\"", re.S)
MAX_BYTES = 400_000


def _calls() -> list[tuple[str, str]]:
    found = []
    for nb in sorted((ROOT / "notebooks").glob("*.ipynb")):
        cells = json.loads(nb.read_text(encoding="utf-8"))["cells"]
        for cell in cells:
            if cell["cell_type"] == "code":
                found += [(nb.name, n) for n in CALL.findall("".join(cell["source"]))]
    return found


CALLS = _calls()


def test_at_least_five_lessons_show_the_live_viewer():
    assert len({nb for nb, _ in CALLS}) >= 5, CALLS


@pytest.mark.parametrize("lesson,name", CALLS, ids=[n for _, n in CALLS])
def test_the_live_viewer_has_its_picture(lesson, name):
    from PIL import Image

    sys.path.insert(0, str(ROOT / "book" / "_ext"))
    from orientviz_book import viewer_snapshot_path

    path = viewer_snapshot_path(ROOT / "book", name)
    assert path.is_file(), f"{lesson}: no {path} (python tools/make_lesson_snapshots.py)"
    assert path.stat().st_size < MAX_BYTES, f"{path} is {path.stat().st_size} bytes"
    rgb = np.asarray(Image.open(path).convert("RGB"), dtype=float)
    assert rgb.shape[0] >= 400 and rgb.shape[1] >= 600
    assert rgb.std() > 10, f"{path} is blank"


def test_snapshot_key_is_the_viewers():
    sys.path.insert(0, str(ROOT / "book" / "_ext"))
    from orientviz_book import VIEWER_SNAPSHOT_KEY

    from orientviz.viewer.live import SNAPSHOT_KEY

    assert VIEWER_SNAPSHOT_KEY == SNAPSHOT_KEY
