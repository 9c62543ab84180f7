"""Figures of relative orientation: parallax fields, passes, influence, precision.

Every function takes results (arrays, :class:`~orientviz.widgets.plotter.PlotterView`,
:class:`~orientviz.orientation.plotter.OrientationRun`, dicts of numbers), draws into
``ax`` (a new figure if None) and returns the Figure. matplotlib is imported inside.
Model coordinates in machine mm, angles in centesimal minutes (c).
"""

from __future__ import annotations

import io
from collections.abc import Mapping, Sequence

import numpy as np

from ..units import RHO_C
from .style import subplots

ELEMENT_LABELS = ("by", "bz", "ω", "φ", "κ")
#: Arrow colours of the parallax field (RGBA of tab:blue for p < 0, tab:red for p ≥ 0).
_ARROW_RGBA = np.array([[31, 119, 180, 255], [214, 39, 40, 255]]) / 255.0


def _axes(ax, figsize=(7.0, 4.8)):

    if ax is None:
        fig, ax = subplots(figsize=figsize)
        return fig, ax
    return ax.figure, ax


def _nice(x: float) -> float:
    """A 1-2-5 number ≤ x."""
    if not np.isfinite(x) or x <= 0:
        return 1.0
    e = 10 ** np.floor(np.log10(x))
    for m in (5, 2, 1):
        if m * e <= x:
            return float(m * e)
    return float(e)


def _exaggeration(view) -> float:
    # arrows point along Y: the longest one spans 90 % of the row spacing
    spacing = float(abs(view.Y[1, 0] - view.Y[0, 0])) if view.Y.shape[0] > 1 else 50.0
    pmax = float(np.abs(view.p).max())
    return _nice(0.9 * spacing / pmax) if pmax > 0 else 1.0


def plot_parallax_field(view, ax=None, *, exaggeration: float | None = None):
    """Y-parallaxes over the model as arrows, with the readings at the scheme points.

    Parameters
    ----------
    view : PlotterView
        From :class:`orientviz.widgets.plotter.VirtualPlotter` (fields ``X``, ``Y``,
        ``p``, ``readings``, ``rms``).
    ax : matplotlib Axes, optional
    exaggeration : float, optional
        Arrow length per mm of parallax (default: chosen from the largest parallax, a
        1-2-5 number; shown in the title).

    Returns
    -------
    matplotlib.figure.Figure
        The artists are kept on ``ax`` for :func:`update_parallax_field`.
    """
    fig, ax = _axes(ax)
    ex = _exaggeration(view) if exaggeration is None else float(exaggeration)
    colors = _ARROW_RGBA[(view.p.ravel() >= 0).astype(np.intp)]
    # changing artists (zorder 3.5, 4) above the static ones: a blit draws the same image
    q = ax.quiver(
        view.X.ravel(), view.Y.ravel(), np.zeros(view.p.size), ex * view.p.ravel(),
        color=colors, angles="xy", scale_units="xy", scale=1.0, width=0.004, zorder=3.5,
    )  # fmt: skip
    scheme_artists = _draw_scheme(ax, view.readings)
    b = float(view.X.max())
    ax.plot([0, b], [0, 0], "k-", lw=2, alpha=0.4)
    ax.plot([0, b], [0, 0], "ko", ms=6)
    ax.set_xlabel("X along the base [machine mm]")
    ax.set_ylabel("Y [machine mm]")
    d = float(np.abs(view.Y).max())
    ax.set_xlim(-0.1 * b, 1.3 * b)
    ax.set_ylim(-1.25 * d, 1.25 * d)
    info = ax.text(0.01, 0.99, "", transform=ax.transAxes, va="top", fontsize=8, zorder=4)
    ax.set_title(
        "y-parallax p_y (red +, blue −; arrows exaggerated ×N), readings and rms in µm",
        fontsize=10,
    )
    ax._orientviz_parallax = {
        "quiver": q, **scheme_artists, "info": info, "fixed": exaggeration,
        "background": None, "background_key": None, "grid": (view.X, view.Y),
        "zeros": np.zeros(view.p.size),
    }  # fmt: skip
    update_parallax_field(ax, view)
    return fig


def _draw_scheme(ax, r) -> dict:
    """Scheme points, their numbers (static) and reading labels (changing) of readings r.

    Labels are plain texts shifted by a few points (cheaper to draw than annotations;
    text is most of the redraw time).
    """
    from matplotlib.transforms import offset_copy

    fig = ax.figure
    name_at = offset_copy(ax.transData, fig=fig, x=-12, y=5, units="points")
    value_at = offset_copy(ax.transData, fig=fig, x=7, y=-3, units="points")
    pts = ax.scatter(r.X, r.Y, s=60, facecolor="none", edgecolor="k", zorder=3)
    names = [
        ax.text(x, y, name, transform=name_at, fontsize=8)
        for x, y, name in zip(r.X, r.Y, r.scheme.labels)
    ]
    labels = [ax.text(x, y, "", transform=value_at, fontsize=8, zorder=4) for x, y in zip(r.X, r.Y)]
    return {"points": pts, "names": names, "labels": labels, "scheme": r.scheme.name}


def _redraw_scheme(ax, r) -> None:
    """Replace the scheme artists after a change of scheme (the blit background too)."""
    a = ax._orientviz_parallax
    animated = a["quiver"].get_animated()
    for art in (a["points"], *a["names"], *a["labels"]):
        art.remove()
    a.update(_draw_scheme(ax, r))
    for lab in a["labels"]:
        lab.set_animated(animated)
    a["background"] = None


def update_parallax_field(ax, view) -> None:
    """Update the arrows, readings and info text of :func:`plot_parallax_field` in place.

    Only data change: arrow lengths and colours (``set_UVC``, an RGBA array), the texts
    (``set_text``, changed strings only) and, if the grid is not the one drawn, the
    arrow positions (``set_offsets``). Nothing is re-created and no layout is run.
    """
    a = ax._orientviz_parallax
    ex = _exaggeration(view) if a["fixed"] is None else float(a["fixed"])
    p = view.p.ravel()
    q = a["quiver"]
    if a["zeros"].size != p.size:
        a["zeros"] = np.zeros(p.size)
    q.set_UVC(a["zeros"], ex * p)
    q.set_facecolor(_ARROW_RGBA[(p >= 0).astype(np.intp)])
    if view.X is not a["grid"][0] or view.Y is not a["grid"][1]:
        q.set_offsets(np.column_stack([view.X.ravel(), view.Y.ravel()]))
        a["grid"] = (view.X, view.Y)
    r = view.readings
    if r.scheme.name != a["scheme"]:
        _redraw_scheme(ax, r)
    for lab, val in zip(a["labels"], r.parallax):
        text = f"{val * 1000:+.0f}"
        if lab.get_text() != text:
            lab.set_text(text)
    a["info"].set_text(f"×{ex:g} · rms {view.rms * 1000:.0f}")  # few glyphs: fast redraw


def blit_parallax_field(ax, view) -> None:
    """Fast redraw of :func:`plot_parallax_field`: only arrows, labels and legend text.

    The static parts (axes, ticks, base line, points) are drawn once and kept as a
    background; each call restores it and draws the changing artists on top
    (blitting; works with the Agg canvas and with ipympl). The changing artists are
    then *animated*: use :func:`update_parallax_field` + a normal draw for saving.
    """
    a = ax._orientviz_parallax
    canvas = ax.figure.canvas
    update_parallax_field(ax, view)  # may replace the scheme artists (new background)
    dynamic = [a["quiver"], a["info"], *a["labels"]]
    key = (canvas.get_width_height(), ax.figure.dpi, id(canvas))
    if a["background"] is None or a["background_key"] != key:  # first call, resize, scheme
        for art in dynamic:
            art.set_animated(True)
        canvas.draw()
        a["background"] = canvas.copy_from_bbox(ax.bbox)
        a["background_key"] = key
    canvas.restore_region(a["background"])
    for art in dynamic:
        ax.draw_artist(art)
    canvas.blit(ax.bbox)


def parallax_field_png(ax, view, *, compress_level: int = 1) -> bytes:
    """Blit :func:`plot_parallax_field` to ``view`` and return the canvas as PNG bytes.

    For front ends without a live matplotlib canvas (the inline backend): the figure
    is redrawn by blitting into its Agg buffer (:func:`blit_parallax_field`) and the
    buffer is encoded directly (Pillow, fast compression), instead of a full
    ``savefig`` with a tight bounding box. The figure's canvas must be an Agg canvas.

    Parameters
    ----------
    ax : matplotlib Axes
        Made by :func:`plot_parallax_field`.
    view : PlotterView
    compress_level : int
        zlib level 0-9 of the PNG (1: fast; for this figure the file is only about 10 %
        larger than at the default 6, 0 would be 30 times larger).

    Returns
    -------
    bytes
        The PNG file, for example for ``ipywidgets.Image(value=..., format="png")``.
    """
    from PIL import Image

    blit_parallax_field(ax, view)
    canvas = ax.figure.canvas
    w, h = canvas.get_width_height(physical=True)
    img = Image.frombuffer("RGBA", (w, h), canvas.buffer_rgba(), "raw", "RGBA", 0, 1)
    out = io.BytesIO()
    img.save(out, format="png", compress_level=int(compress_level))
    return out.getvalue()


def plot_pass_log(runs: Mapping[str, object] | Sequence, ax=None, *, tol_c: float = 1.0):
    """Largest rotation correction per pass (log scale), one line per run.

    Parameters
    ----------
    runs : dict of label → OrientationRun (or list of PassRecord), or one of them
    tol_c : float
        The convergence threshold drawn as a line, centesimal minutes.
    """
    fig, ax = _axes(ax)
    if not isinstance(runs, Mapping):
        runs = {"run": runs}
    for label, run in runs.items():
        passes = getattr(run, "passes", run)
        c = np.array([p.max_rotation_c for p in passes])
        ax.semilogy(np.arange(1, c.size + 1), c, "o-", label=label)
    ax.axhline(tol_c, color="gray", ls="--", lw=1, label=f"converged below {tol_c:g} c")
    ax.set_xlabel("pass")
    ax.set_ylabel("largest rotation correction [c]")
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    return fig


def plot_passes_vs_relief(table: Mapping[str, tuple], ax=None, *, paper=None):
    """Passes needed against relative relief, per formula.

    Parameters
    ----------
    table : dict
        formula → (reliefs, mean passes, min passes, max passes), arrays.
    paper : sequence of (relief, low, high), optional
        The paper's ranges, drawn as grey bars.
    """
    fig, ax = _axes(ax)
    if paper is not None:
        for r, lo, hi in paper:
            lo, hi = (lo - 0.08, hi + 0.08) if lo == hi else (lo, hi)  # a single count: a stub
            ax.plot(
                [100 * r, 100 * r], [lo, hi], color="0.6", lw=8, alpha=0.6, solid_capstyle="butt"
            )
        ax.plot([], [], color="0.6", lw=8, alpha=0.6, label="Kovarik 1968")
    for formula, (rel, mean, lo, hi) in table.items():
        rel = 100 * np.asarray(rel)
        ax.errorbar(
            rel,
            mean,
            yerr=[np.asarray(mean) - lo, np.asarray(hi) - mean],
            marker="o",
            capsize=3,
            label=formula,
        )
    ax.set_xlabel("relative relief [% of the projection distance]")
    ax.set_ylabel("passes until converged")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return fig


def plot_preorientation_error(out: Mapping[str, np.ndarray], ax=None):
    """Absolute error of Δω and Δφ (c) against the size of the rotations, round vs exact formulas.

    Parameters
    ----------
    out : dict
        From :func:`orientviz.orientation.plotter.preorientation_error`.
    """
    fig, ax = _axes(ax)
    a = out["alpha_c"]
    for key, style in (("round", "-"), ("exact", "--")):
        for j, name in ((0, "Δω"), (1, "Δφ")):
            ax.loglog(a, np.abs(out[key][:, j]) + 1e-6, style, marker="o", label=f"{name}, {key}")
    ax.loglog(a, 0.01 * a, ":", color="gray", label="1 % of the rotation")
    ax.set_xlabel("true rotation [c]")
    ax.set_ylabel("|computed − true| [c]")
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    return fig


def plot_influence(G: np.ndarray, labels: Sequence[str], ax=None, *, names=ELEMENT_LABELS):
    """Influence of each point's parallax on each element (rows of (AᵀA)⁻¹Aᵀ), normalised per row."""
    fig, ax = _axes(ax, figsize=(7, 3.2))
    G = np.asarray(G, dtype=float)
    M = G / np.abs(G).max(axis=1, keepdims=True)
    im = ax.imshow(M, cmap="RdBu_r", vmin=-1, vmax=1, aspect="auto")
    ax.set_xticks(range(len(labels)), [f"P{s}" for s in labels])
    ax.set_yticks(range(len(names)), names)
    for i in range(M.shape[0]):
        for j in range(M.shape[1]):
            if abs(M[i, j]) < 1e-9:
                ax.text(j, i, "0", ha="center", va="center", fontsize=8)
    fig.colorbar(im, ax=ax, label="influence / row maximum")
    ax.set_title("which point influences which element", fontsize=10)
    return fig


def plot_scheme_precision(table: Mapping[str, np.ndarray], ax=None):
    """σ of ω, φ, κ (c) per point scheme as grouped bars.

    Parameters
    ----------
    table : dict
        scheme name → σ of (by, bz, ω, φ, κ) in (mm, mm, rad, rad, rad).
    """
    fig, ax = _axes(ax)
    names = list(table)
    w = 0.8 / max(len(names), 1)
    for i, n in enumerate(names):
        s = np.asarray(table[n])[2:] * RHO_C
        ax.bar(np.arange(3) + i * w, s, width=w, label=n)
    ax.set_xticks(np.arange(3) + 0.4 - w / 2, ["σω", "σφ", "σκ"])
    ax.set_ylabel("standard deviation [c]")
    ax.legend(fontsize=8)
    return fig
