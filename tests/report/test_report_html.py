"""The HTML report: self-contained, parseable, escaped, with figures (or without them
when matplotlib is missing), and the same numbers as recomputed from the solution."""

from __future__ import annotations

import base64
import sys
from html.parser import HTMLParser

import numpy as np
import pytest
from test_report_sections import (
    BLOCK_SECTIONS,
    independent_check_rms_mm,
    independent_sigma0_and_r,
)

import orientviz as ov
from orientviz.io.datasets import dataset_path
from orientviz.report import build_report, html_report

pytest.importorskip("matplotlib")


class Collect(HTMLParser):
    """Tags with their attributes, key/value rows (th, td) and data-table rows."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[tuple[str, dict[str, str | None]]] = []
        self.rows: list[list[str]] = []
        self._row: list[str] | None = None
        self._cell: list[str] | None = None
        self.open: list[str] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))
        if tag not in ("meta", "img", "br", "hr", "link", "input"):
            self.open.append(tag)
        if tag == "tr":
            self._row = []
        elif tag in ("td", "th") and self._row is not None:
            self._cell = []

    def handle_endtag(self, tag):
        assert self.open and self.open[-1] == tag, f"</{tag}> closes {self.open[-1:]}"
        self.open.pop()
        if tag in ("td", "th") and self._cell is not None:
            self._row.append("".join(self._cell).strip())
            self._cell = None
        elif tag == "tr" and self._row is not None:
            self.rows.append(self._row)
            self._row = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def parse(text: str) -> Collect:
    p = Collect()
    p.feed(text)
    p.close()
    assert not p.open, f"unclosed tags {p.open}"
    return p


def kv(p: Collect, label: str) -> str:
    hits = [r[1] for r in p.rows if len(r) == 2 and r[0] == label]
    assert hits, f"no row {label!r}"
    return hits[0]


@pytest.fixture(scope="module")
def strip_html(tmp_path_factory):
    problem = ov.load_problem(dataset_path("block_strip"))
    solution = ov.solve_problem(problem)
    path = ov.write_report(problem, solution, tmp_path_factory.mktemp("r") / "report.html")
    return problem, solution, path.read_text(encoding="utf-8"), path


def test_html_is_self_contained_and_parses(strip_html):
    _, _, text, path = strip_html
    p = parse(text)
    tags = [t for t, _ in p.tags]
    assert "script" not in tags and "link" not in tags and "iframe" not in tags
    for _tag, attrs in p.tags:
        for key in ("src", "href"):
            value = attrs.get(key)
            if value is not None:
                assert not value.lower().startswith(("http://", "https://", "//")), value
                assert value.startswith(("#", "data:image/png;base64,")), value
    imgs = [a["src"] for t, a in p.tags if t == "img"]
    assert len(imgs) >= 4  # overview, per-image σ, point precision, w histogram
    for src in imgs:
        png = base64.b64decode(src.split(",", 1)[1], validate=True)
        assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert "http://" not in text and "https://" not in text
    assert path.stat().st_size < 2_000_000


def test_html_has_every_section_and_the_recomputed_numbers(strip_html):
    problem, solution, text, _ = strip_html
    p = parse(text)
    ids = [a.get("id") for t, a in p.tags if t == "section"]
    assert ids == BLOCK_SECTIONS
    sigma0, r = independent_sigma0_and_r(problem, solution)
    assert float(kv(p, "σ0 a posteriori (unit weight)")) == pytest.approx(sigma0, abs=5e-5)
    assert int(kv(p, "redundancy r")) == r
    row = next(r_ for r_ in p.rows if r_ and r_[0] == "μ (r.m.s.)")
    assert [float(x) for x in row[1:]] == pytest.approx(
        independent_check_rms_mm(problem, solution), abs=0.051
    )


def test_block_compact_report_is_small(tmp_path):
    problem = ov.load_problem(dataset_path("block_compact"))
    path = ov.write_report(problem, ov.solve_problem(problem), tmp_path / "c.html")
    assert 0 < path.stat().st_size < 2_000_000
    parse(path.read_text(encoding="utf-8"))


def test_all_text_is_escaped():
    problem = ov.load_problem(dataset_path("resection_example"))
    solution = ov.solve_problem(problem)
    problem.name = "<script>alert('x')</script> & <b>"
    problem.description = 'say "hi" <img src=http://example.com/x.png>'
    text = html_report(build_report(problem, solution), figures=False)
    assert "<script" not in text and "<b>" not in text and "<img src=http" not in text
    assert "&lt;script&gt;alert(&#x27;x&#x27;)&lt;/script&gt; &amp; &lt;b&gt;" in text
    p = parse(text)
    assert not [t for t, _ in p.tags if t in ("script", "b", "img")]


def test_without_matplotlib_the_report_says_figures_are_omitted(monkeypatch, tmp_path):
    problem = ov.load_problem(dataset_path("block_strip"))
    solution = ov.solve_problem(problem)
    monkeypatch.setitem(sys.modules, "orientviz.plot.report_figures", None)  # import fails
    path = ov.write_report(problem, solution, tmp_path / "nofig.html")
    text = path.read_text(encoding="utf-8")
    p = parse(text)
    assert not [t for t, _ in p.tags if t == "img"]
    assert "Figures omitted" in text and "matplotlib is not installed" in text
    assert [a.get("id") for t, a in p.tags if t == "section"] == BLOCK_SECTIONS


def test_big_block_is_thinned_and_stays_small(tmp_path):
    from orientviz.io.problem import problem_from_block
    from orientviz.simulate import simulate_block

    sim = simulate_block(4, 12, rng=5, n_check=4)
    problem = problem_from_block(sim.block, name="sim")
    solution = ov.solve_problem(problem)
    path = ov.write_report(problem, solution, tmp_path / "big.html")
    p = parse(path.read_text(encoding="utf-8"))
    assert path.stat().st_size < 2_000_000
    # every image is in the exterior-orientation table (48 < the row limit)
    names = {r[0] for r in p.rows if r}
    assert set(sim.block.images.ids) <= names
    assert np.isfinite(solution.adjustment.sigma0)
