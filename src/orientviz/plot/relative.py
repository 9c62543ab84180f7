"""Figures of relative orientation: parallax fields, passes, influence, precision.

Every function takes results (arrays, :class:`~orientviz.widgets.plotter.PlotterView`,
:class:`~orientviz.orientation.plotter.OrientationRun`, dicts of numbers), draws into
``ax`` (a new figure if None) and returns the Figure. matplotlib is imported inside.
Model coordinates in machine mm, angles in centesimal minutes (c).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

ELEMENT_LABELS = ("by", "bz", "ω", "φ", "κ")


def _axes(ax, figsize=(7.0, 4.8)):
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=figsize)
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
    colors = np.where(view.p.ravel() >= 0, "tab:red", "tab:blue")
    q = ax.quiver(
        view.X.ravel(), view.Y.ravel(), np.zeros(view.p.size), ex * view.p.ravel(),
        color=colors, angles="xy", scale_units="xy", scale=1.0, width=0.004,
    )  # fmt: skip
    r = view.readings
    pts = ax.scatter(r.X, r.Y, s=60, facecolor="none", edgecolor="k", zorder=3)
    for x, y, name in zip(r.X, r.Y, r.scheme.labels):  # static point numbers
        ax.annotate(name, (x, y), xytext=(-12, 5), textcoords="offset points", fontsize=7)
    labels = [  # the readings change: few glyphs, no boxes (text dominates redraw time)
        ax.annotate("", (x, y), xytext=(7, -3), textcoords="offset points", fontsize=7)
        for x, y in zip(r.X, r.Y)
    ]
    b = float(view.X.max())
    ax.plot([0, b], [0, 0], "k-", lw=2, alpha=0.4)
    ax.plot([0, b], [0, 0], "ko", ms=6)
    ax.set_xlabel("X along the base [machine mm]")
    ax.set_ylabel("Y [machine mm]")
    d = float(np.abs(view.Y).max())
    ax.set_xlim(-0.1 * b, 1.3 * b)
    ax.set_ylim(-1.25 * d, 1.25 * d)
    info = ax.text(0.01, 0.99, "", transform=ax.transAxes, va="top", fontsize=8)
    ax.set_title(
        "y-parallax p_y (red +, blue −; arrows exaggerated ×N), readings and rms in µm",
        fontsize=10,
    )
    ax._orientviz_parallax = {
        "quiver": q, "points": pts, "labels": labels, "info": info, "fixed": exaggeration,
        "background": None,
    }  # fmt: skip
    update_parallax_field(ax, view)
    return fig


def update_parallax_field(ax, view) -> None:
    """Redraw the arrows, readings and title of :func:`plot_parallax_field` in place."""
    a = ax._orientviz_parallax
    ex = _exaggeration(view) if a["fixed"] is None else float(a["fixed"])
    p = view.p.ravel()
    a["quiver"].set_UVC(np.zeros(p.size), ex * p)
    a["quiver"].set_color(np.where(p >= 0, "tab:red", "tab:blue"))
    r = view.readings
    for lab, val in zip(a["labels"], r.parallax):
        lab.set_text(f"{val * 1000:+.0f}")
    q = a["quiver"]
    q.set_offsets(np.column_stack([view.X.ravel(), view.Y.ravel()]))
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
    dynamic = [a["quiver"], a["info"], *a["labels"]]
    if a["background"] is None:
        for art in dynamic:
            art.set_animated(True)
        canvas.draw()
        a["background"] = canvas.copy_from_bbox(ax.bbox)
    update_parallax_field(ax, view)
    canvas.restore_region(a["background"])
    for art in dynamic:
        ax.draw_artist(art)
    canvas.blit(ax.bbox)


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
    """|error| of Δω and Δφ (c) against the size of the rotations, round vs exact formulas.

    Parameters
    ----------
    out : dict
        From :func:`orientviz.orientation.preorient.preorientation_error`.
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
    from ..units import RHO_C

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
