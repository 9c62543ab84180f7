"""Figures readable in the book's column: the rules of orientviz.plot.style, measured.

The book embeds each figure as a 100-dpi PNG, scaled down to the column (624 px). A text
of s pt in a figure W in wide is then s/72 · 100 · min(1, 624/(100 W)) px high (624 px:
the column in a 1280-px window): the book-wide cause of unreadable figures was 11–14-inch
figures with 7–9 pt labels. Every figure of plot/ and widgets/ is now made by plot.style
(width capped at 6.2 in, text sizes
from one table); these tests keep it so. The built book is measured figure by figure in
tests/book/test_book.py (ORIENTVIZ_FIGURE_AUDIT).
"""

from __future__ import annotations

import ast
import pathlib

import numpy as np
import pytest

pytest.importorskip("matplotlib")
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from orientviz.plot import style  # noqa: E402

ROOT = pathlib.Path(__file__).parents[2]
FIGURE_MODULES = sorted(
    p
    for d in ("plot", "widgets")
    for p in (ROOT / "src/orientviz" / d).glob("*.py")
    if p.name != "style.py"
)
SIZE_KEYWORDS = {"fontsize", "labelsize", "title_fontsize", "size"}


def _calls(tree):
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            yield node


@pytest.mark.parametrize("path", FIGURE_MODULES, ids=[p.name for p in FIGURE_MODULES])
def test_figures_are_made_by_the_style_module(path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for call in _calls(tree):
        f = call.func
        if isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name) and f.value.id == "plt":
            assert f.attr not in ("subplots", "figure", "subplot_mosaic"), (
                f"{path.name}:{call.lineno}: plt.{f.attr}() — use orientviz.plot.style."
                f"{'subplots' if f.attr != 'figure' else 'figure'} (width cap, readable fonts)"
            )
        for kw in call.keywords:
            if kw.arg in SIZE_KEYWORDS and isinstance(kw.value, ast.Constant):
                v = kw.value.value
                if isinstance(v, (int, float)) and not isinstance(v, bool) and kw.arg != "size":
                    assert v >= style.MIN_FONT_PT, (
                        f"{path.name}:{call.lineno}: {kw.arg}={v} pt is below {style.MIN_FONT_PT} pt"
                    )


def test_the_rule_itself_a_7_inch_figure_with_the_smallest_font_is_readable():
    px = style.MIN_FONT_PT / 72 * style.BOOK_DPI * min(1, style.COLUMN_PX / (style.BOOK_DPI * style.MAX_WIDTH_IN))
    assert px >= style.MIN_TEXT_PX
    w, h = style.figure_size(14.0, 5.0)
    assert w == style.MAX_WIDTH_IN and h == pytest.approx(5.0 * style.MAX_WIDTH_IN / 14.0)
    assert style.figure_size(5.0, 4.0) == (5.0, 4.0)


def test_a_wide_figure_is_capped_and_a_raw_wide_one_would_not_be_readable():
    fig, ax = style.subplots(1, 3, figsize=(14, 4.8))
    for a in ax:
        a.set_title("panel")
        a.plot([0, 1], [0, 1])
    assert min(px for px, _ in style.text_sizes_px(fig)) >= style.MIN_TEXT_PX
    raw, rax = plt.subplots(1, 3, figsize=(14, 4.8))
    for a in rax:
        a.set_title("panel", fontsize=8)
        a.tick_params(labelsize=8)
    assert min(px for px, _ in style.text_sizes_px(raw)) < style.MIN_TEXT_PX  # the measure can fail
    plt.close("all")


def test_book_rc_leaves_interactive_mode_alone():
    before = matplotlib.is_interactive()
    matplotlib.interactive(not before)
    try:
        with style.book_rc():
            matplotlib.interactive(before)  # as a backend's activation would
        assert matplotlib.is_interactive() == before
    finally:
        matplotlib.interactive(before)


def _lesson_figures():
    from orientviz.plot.datum import plot_datum_ellipses
    from orientviz.plot.epipolar import plot_epipolar_lines
    from orientviz.plot.interior import plot_fiducial_residuals
    from orientviz.plot.lsq import plot_ellipse_check
    from orientviz.plot.sparsity import plot_normal_pattern, plot_reduced_patterns

    rng = np.random.default_rng(0)
    C = np.array([[4.0, 1.0], [1.0, 2.0]])
    xy = rng.uniform(0, 900, (6, 2))
    pairs = np.array([[i, j] for i in range(6) for j in range(i + 1, 6)])
    P = np.eye(8, dtype=bool) | (np.abs(np.subtract.outer(range(8), range(8))) == 2)
    E = np.array([[0.0, -1.0, 0.1], [1.0, 0.0, -92.0], [-0.1, 92.0, 0.0]])
    return {
        "ellipse_check": plot_ellipse_check(rng.multivariate_normal([0, 0], C, 200), [0, 0], C, unit="mm"),
        "fiducials": plot_fiducial_residuals(xy - 450, {"a": rng.normal(0, 0.01, (6, 2)), "b": rng.normal(0, 0.002, (6, 2))}),
        "epipolar": plot_epipolar_lines(rng.uniform(-90, 90, (4, 2)), rng.uniform(-90, 90, (4, 2)), E, 152.0),
        "datum": plot_datum_ellipses(xy, pairs, {"x": np.eye(12) * 1e-6, "y": np.eye(12) * 4e-6, "z": np.eye(12) * 2e-6}),
        "normal_pattern": plot_normal_pattern(np.eye(12, dtype=bool) | np.eye(12, k=5, dtype=bool) | np.eye(12, k=-5, dtype=bool), 4),
        "reduced": plot_reduced_patterns({"one": (P, None), "two": (P, np.arange(8)[::-1]), "three": (P, None)}),
    }  # fmt: skip


def test_the_lesson_figures_are_readable_in_the_column():
    for name, fig in _lesson_figures().items():
        sizes = style.text_sizes_px(fig)
        assert sizes, name
        assert sizes[0][0] >= style.MIN_TEXT_PX, f"{name}: {sizes[0][1]!r} is {sizes[0][0]:.1f} px"
    plt.close("all")
