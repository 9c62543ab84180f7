"""Figure sizes and font sizes that stay readable in the book's column.

The book shows a figure as a PNG (matplotlib's inline backend: 100 dpi, tight bounding
box) scaled down to the width of its text column, about :data:`COLUMN_PX` pixels. A
text of ``s`` points in a figure ``W`` inches wide is then drawn

    h = s/72 · 100 · min(1, COLUMN_PX / (100 W))   pixels high (the em size),

so what decides readability is the ratio of font size to figure width, not the dpi:
a 13-inch figure with 7-point labels ends up at 4.7 px. The rules, used by every
function in :mod:`orientviz.plot` and :mod:`orientviz.widgets`:

* figures are at most :data:`MAX_WIDTH_IN` wide (:func:`figure_size` caps wider
  requests and keeps the aspect ratio);
* text sizes come from :data:`FONT` (no size below :data:`MIN_FONT_PT`), so at the
  largest width every text is at least :data:`MIN_TEXT_PX` pixels in the column.

:func:`text_sizes_px` measures a finished figure the way the book shows it;
``tests/book`` uses it on the lesson figures and, through :func:`audit_figures` in the
book build, on every figure a lesson shows (widget snapshots included).
"""

from __future__ import annotations

from contextlib import contextmanager

import numpy as np

#: Width of the book's text column in CSS pixels: 624 px measured in a 1280-px wide
#: browser window (pydata theme with both sidebars; 690 px at 1024 and at ≥ 1440 px).
COLUMN_PX: int = 624
#: Resolution of the PNGs the book embeds (matplotlib_inline: figure.dpi = 100).
BOOK_DPI: float = 100.0
#: Widest figure, in inches: one that fills the column without being scaled down.
MAX_WIDTH_IN: float = 6.2
#: Smallest readable text height in the column, px.
MIN_TEXT_PX: float = 10.0
#: Smallest font size, pt: 8 pt is 11.1 px unscaled, and still 10 px when a tight bounding
#: box (labels outside the axes) makes a MAX_WIDTH_IN figure 690 px wide.
MIN_FONT_PT: float = 8.0
#: Font sizes (pt) by role.
FONT: dict[str, float] = {
    "title": 11.0,
    "suptitle": 12.0,
    "label": 10.0,
    "tick": 9.0,
    "legend": 9.0,
    "note": 9.0,
    "small": MIN_FONT_PT,
}

#: rc settings applied while a figure is created by :func:`new_figure`.
RC: dict[str, object] = {
    "font.size": FONT["label"],
    "axes.titlesize": FONT["title"],
    "axes.labelsize": FONT["label"],
    "xtick.labelsize": FONT["tick"],
    "ytick.labelsize": FONT["tick"],
    "legend.fontsize": FONT["legend"],
    "legend.title_fontsize": FONT["legend"],
    "figure.titlesize": FONT["suptitle"],
}


def figure_size(width: float, height: float) -> tuple[float, float]:
    """``(width, height)`` in inches, scaled down to at most :data:`MAX_WIDTH_IN` wide."""
    if width <= MAX_WIDTH_IN:
        return (float(width), float(height))
    f = MAX_WIDTH_IN / width
    return (MAX_WIDTH_IN, float(height) * f)


@contextmanager
def book_rc():
    """Context in which new figures, axes and texts use :data:`RC` (readable sizes).

    Only the keys of :data:`RC` are set and restored. (``matplotlib.rc_context`` restores
    *every* setting, ``interactive`` included: a figure that activates the inline backend
    inside it would switch interactive mode off again, and later figures of the notebook
    would no longer be shown.)
    """
    import matplotlib as mpl

    saved = {k: mpl.rcParams[k] for k in RC}
    mpl.rcParams.update(RC)
    try:
        yield
    finally:
        mpl.rcParams.update(saved)


def new_figure(figsize: tuple[float, float] = (MAX_WIDTH_IN, 4.5), *, nrows: int = 1,
               ncols: int = 1, projection: str | None = None, **kwargs):  # fmt: skip
    """A new figure with axes, sized by :func:`figure_size` and fonts by :data:`RC`.

    Parameters
    ----------
    figsize : (float, float)
        Wished size in inches; wider than :data:`MAX_WIDTH_IN` is scaled down.
    nrows, ncols : int
        Subplot grid (as :func:`matplotlib.pyplot.subplots`).
    projection : str, optional
        e.g. ``"3d"``: one axes with this projection (nrows = ncols = 1).
    **kwargs
        Passed to :func:`matplotlib.pyplot.subplots` (``width_ratios``, ``layout``…).

    Returns
    -------
    (Figure, Axes or ndarray of Axes)
    """
    import matplotlib.pyplot as plt

    size = figure_size(*figsize)
    with book_rc():
        if projection is not None:
            fig = plt.figure(figsize=size)
            return fig, fig.add_subplot(projection=projection)
        return plt.subplots(nrows, ncols, figsize=size, **kwargs)


def text_sizes_px(
    fig, *, column_px: float = COLUMN_PX, dpi: float = BOOK_DPI
) -> list[tuple[float, str]]:
    """Height (px) of every visible, non-empty text of ``fig`` as shown in the book.

    The figure is rendered as the book renders it (``dpi``, tight bounding box); the
    PNG is scaled to ``column_px`` if wider. Returns ``(px, text)`` pairs, smallest first.
    """
    return _sizes_and_width(fig, column_px, dpi)[0]


def _sizes_and_width(fig, column_px: float, dpi: float) -> tuple[list[tuple[float, str]], int]:
    """:func:`text_sizes_px` and the width (px) of the PNG it rendered."""
    import io

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    width_px = _png_width(buf.getvalue())
    scale = min(1.0, column_px / width_px)
    out = []
    for t in fig.findobj(lambda a: hasattr(a, "get_fontsize") and hasattr(a, "get_text")):
        if not t.get_visible() or not str(t.get_text()).strip():
            continue
        if not _on_figure(t, fig):
            continue
        out.append((float(t.get_fontsize()) / 72.0 * dpi * scale, str(t.get_text())))
    return sorted(out), width_px


def _png_width(data: bytes) -> int:
    # PNG: 8-byte signature, then the IHDR chunk with width, height (big-endian)
    return int.from_bytes(data[16:20], "big")


def _on_figure(text, fig) -> bool:
    """False for tick labels outside their axis' view (matplotlib keeps spare ones)."""
    try:
        bb = text.get_window_extent(renderer=fig.canvas.get_renderer())
    except Exception:  # texts without a renderer position (e.g. unused offsets)
        return False
    fb = fig.bbox
    return bool(np.isfinite([bb.x0, bb.y0]).all() and bb.width > 0 and bb.x1 > fb.x0 - 1e3)


def subplots(*args, figsize: tuple[float, float] | None = None, **kwargs):
    """:func:`matplotlib.pyplot.subplots` with the book's rules: width capped by
    :func:`figure_size`, text sizes from :data:`RC`. Every figure of :mod:`orientviz.plot`
    and :mod:`orientviz.widgets` is made here or by :func:`figure`."""
    import matplotlib.pyplot as plt

    size = figure_size(*(figsize or (6.4, 4.8)))
    with book_rc():
        return plt.subplots(*args, figsize=size, **kwargs)


def figure(figsize: tuple[float, float] | None = None, **kwargs):
    """:func:`matplotlib.pyplot.figure` with the book's rules (see :func:`subplots`)."""
    import matplotlib.pyplot as plt

    size = figure_size(*(figsize or (6.4, 4.8)))
    with book_rc():
        return plt.figure(figsize=size, **kwargs)


def audit_figures(path: str, label: str) -> bool:
    """Record the text sizes of every figure an IPython kernel displays (for the book's test).

    Wraps the kernel's PNG formatter of matplotlib figures: before a figure is shown,
    one JSON line ``{"notebook", "index", "min_px", "text", "width_px", "figsize_in"}`` is
    appended to ``path`` (:func:`text_sizes_px` at the book's column width). Figures shown
    inside widgets' Output areas pass the same formatter. The book's ``conf.py`` installs
    it in a removed first cell when ``ORIENTVIZ_FIGURE_AUDIT`` names a file.

    Returns
    -------
    bool
        False outside IPython (nothing installed).
    """
    import json

    try:
        from IPython import get_ipython
    except ImportError:  # pragma: no cover - IPython is there when a kernel runs this
        return False
    ip = get_ipython()
    if ip is None:
        return False
    import matplotlib.pyplot as plt  # activates the inline backend and its formatters
    from matplotlib.figure import Figure

    plt.close(plt.figure())  # the inline backend registers its formatters on first use
    fmt = ip.display_formatter.formatters["image/png"]
    try:
        original = fmt.lookup_by_type(Figure)
    except KeyError:  # a backend without PNG display: nothing is shown, nothing to measure
        return False
    count = {"n": 0}

    def measured(fig, *args, **kwargs):
        sizes, width_px = _sizes_and_width(fig, COLUMN_PX, BOOK_DPI)
        rec = {
            "notebook": label,
            "index": count["n"],
            "min_px": sizes[0][0] if sizes else None,
            "text": sizes[0][1][:60] if sizes else "",
            "width_px": width_px,
            "figsize_in": [float(v) for v in fig.get_size_inches()],
        }
        count["n"] += 1
        with open(path, "a", encoding="utf-8") as f:
            f.write(json.dumps(rec, ensure_ascii=False) + "\n")
        return original(fig, *args, **kwargs)

    fmt.for_type(Figure, measured)
    return True
