"""The book builds offline with every lesson executed, and needs no network to render math."""

from __future__ import annotations

import importlib.util
import json
import os
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


#: Error output on a built page: a traceback (myst-nb's class) or its first line.
ERROR_MARKS = ('class="output traceback', "Traceback (most recent call last)")
#: An iframe to a local server (a viewer that is gone when the page is read).
LOCAL_IFRAME = re.compile(r"<iframe[^>]+src=[\"']https?://(127\.0\.0\.1|localhost|0\.0\.0\.0)", re.I)


def check_no_error_output(out: pathlib.Path) -> None:
    """No page shows an error (also inside widget snapshots) or embeds a local server."""
    for page in sorted(out.rglob("*.html")):
        text = page.read_text(encoding="utf-8")
        rel = page.relative_to(out).as_posix()
        for mark in ERROR_MARKS:
            assert mark not in text, f"{rel}: error output on the page ({mark!r})"
        assert not LOCAL_IFRAME.search(text), f"{rel}: an iframe to a local server"


def check_figure_audit(audit: pathlib.Path) -> list[dict]:
    """Every figure a lesson showed is readable in the column (plot/style.py's measure)."""
    from orientviz.plot.style import MIN_TEXT_PX

    records = [json.loads(line) for line in audit.read_text(encoding="utf-8").splitlines()]
    lessons = {p.stem for p in (ROOT / "notebooks").glob("*.ipynb")}
    assert records and {r["notebook"] for r in records} <= lessons
    small = [r for r in records if r["min_px"] is not None and r["min_px"] < MIN_TEXT_PX]
    assert not small, f"figures with text below {MIN_TEXT_PX} px in the column:\n" + "\n".join(
        f"  {r['notebook']} figure {r['index']}: {r['min_px']:.1f} px ({r['text']!r}), "
        f"{r['figsize_in'][0]:.1f} in wide, PNG {r['width_px']} px"
        for r in small
    )
    return records


def test_introduction_lists_every_lesson_by_its_number():
    text = (ROOT / "book/chapters/introduction.md").read_text(encoding="utf-8")
    listed = re.findall(r"^\| (\d\d) \|", text, re.M)
    files = sorted(p.stem[:2] for p in (ROOT / "notebooks").glob("*.ipynb"))
    assert listed == files
    teaching = (ROOT / "book/chapters/teaching.md").read_text(encoding="utf-8")
    assert "python tools/make_student_release.py" in teaching
    for stem in files:
        assert re.search(rf"\b{stem}\b", teaching), f"lesson {stem} missing from the teachers' chapter"


@pytest.mark.slow
def test_book_builds_offline(tmp_path, executed_lessons):
    pytest.importorskip("myst_nb")
    out = tmp_path / "html"
    audit = tmp_path / "figure-audit.jsonl"
    env = dict(os.environ, ORIENTVIZ_FIGURE_AUDIT=str(audit))
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-b", "html", "-q", str(ROOT / "book"), str(out)],
        capture_output=True,
        text=True,
        timeout=1500,
        env=env,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    # the lessons' kernels get CurveZMQ keys (book/conf.py): no unencrypted-TCP warning
    assert "without encryption" not in proc.stdout + proc.stderr
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
        "chapters/teaching.html",
        "chapters/viewer.html",
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
    check_no_error_output(out)
    check_figure_audit(audit)
    for name in lessons:  # the lessons ran here: tests/notebooks need not run them again
        executed = tmp_path / "jupyter_execute" / "lessons" / f"{name}.ipynb"
        source = (ROOT / "notebooks" / f"{name}.ipynb").read_text(encoding="utf-8")
        notebook = json.loads(executed.read_text(encoding="utf-8"))
        executed_lessons[f"{name}.ipynb"] = {"source": source, "notebook": notebook}
