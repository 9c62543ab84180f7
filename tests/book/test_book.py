"""The book builds offline with every lesson executed, and needs no network to render math."""

from __future__ import annotations

import importlib.util
import json
import pathlib
import re
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).parents[2]
#: Lesson apps that draw a figure: their static snapshot in the book must show it.
FIGURE_APPS = (
    "rotation_app(",
    "plotter_app(",
    "absolute_app(",
    "resection_app(",
    "block_app(",
    "radar_app(",
)


def _load_extension():
    spec = importlib.util.spec_from_file_location(
        "orientviz_book", ROOT / "book/_ext/orientviz_book.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def docstring_warnings(log: str) -> list[str]:
    """Sphinx warnings/errors raised by the package's docstrings (API reference pages)."""
    where = re.compile(r"(src/orientviz/|api/generated/).*(WARNING|ERROR):")
    return [line for line in log.splitlines() if where.search(line)]


def check_widget_snapshots(out: pathlib.Path) -> None:
    """Every widget on a lesson page is shown as a static snapshot with its figure or text."""
    ob = _load_extension()
    for nb_path in sorted((ROOT / "notebooks").glob("*.ipynb")):
        page = (out / "lessons" / f"{nb_path.stem}.html").read_text(encoding="utf-8")
        # no widget is left as a bare (invisible without a kernel) widget view
        assert "application/vnd.jupyter.widget-view+json" not in page, nb_path.name
        cells = json.loads(nb_path.read_text(encoding="utf-8"))["cells"]
        code = ["".join(c["source"]) for c in cells if c["cell_type"] == "code"]
        lines = [ln.strip() for src in code for ln in src.splitlines()]
        shown = [ln for ln in lines if ln.startswith(FIGURE_APPS) and not ln.startswith("#")]
        interacts = [ln for ln in lines if "interact(" in ln and not ln.startswith("#")]
        assert "<img" in page, f"{nb_path.name}: no figure on the page"
        snaps = ob.find_snapshots(page)
        assert len(snaps) >= len(shown) + len(interacts), (nb_path.name, len(snaps))
        for snap in snaps:
            assert "<img" in snap or "<pre>" in snap, f"empty widget snapshot in {nb_path.name}"
        with_figure = [s for s in snaps if "<img" in s]
        assert len(with_figure) >= len(shown), f"{nb_path.name}: an app snapshot without its figure"


@pytest.mark.slow
def test_book_builds_offline(tmp_path):
    pytest.importorskip("myst_nb")
    out = tmp_path / "html"
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-b", "html", "-q", str(ROOT / "book"), str(out)],
        capture_output=True,
        text=True,
        timeout=1200,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    bad_docstrings = docstring_warnings(proc.stderr)
    assert not bad_docstrings, "warnings from docstrings:\n" + "\n".join(bad_docstrings[:10])
    pages = {p.relative_to(out).as_posix() for p in out.rglob("*.html")}
    for chapter in (
        "index.html",
        "chapters/conventions.html",
        "chapters/papers.html",
        "chapters/bibliography.html",
        "chapters/command_line.html",
        "chapters/reproductions.html",
        "api/index.html",
    ):
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
    check_widget_snapshots(out)
