"""The book builds offline with every lesson executed, and needs no network to render math."""

from __future__ import annotations

import pathlib
import re
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).parents[2]


@pytest.mark.slow
def test_book_builds_offline(tmp_path):
    pytest.importorskip("myst_nb")
    out = tmp_path / "html"
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-b", "html", "-q", str(ROOT / "book"), str(out)],
        capture_output=True, text=True, timeout=1200,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    pages = {p.relative_to(out).as_posix() for p in out.rglob("*.html")}
    for chapter in ("index.html", "chapters/conventions.html", "chapters/papers.html",
                    "chapters/bibliography.html", "chapters/command_line.html",
                    "chapters/reproductions.html", "api/index.html"):
        assert chapter in pages, f"missing {chapter}"
    lessons = sorted(p.stem for p in (ROOT / "notebooks").glob("*.ipynb"))
    for name in lessons:
        assert f"lessons/{name}.html" in pages, f"lesson {name} not in the book"
    # math is rendered by the bundled MathJax, never fetched from a CDN
    html = {p: p.read_text(encoding="utf-8") for p in out.rglob("*.html")}
    remote = re.compile(r"<script[^>]+src=[\"']https?://")
    cdn = [p.name for p, text in html.items() if remote.search(text)]
    assert not cdn, f"pages load scripts from the network: {cdn[:5]}"
    with_math = [p for p, text in html.items() if "_static/mathjax/" in text]
    assert with_math, "no page loads the bundled MathJax"
    assert (out / "_static" / "mathjax").is_dir()
