"""Figures of the reproductions (pure functions returning a Figure; matplotlib lazily).

:func:`plot_kovarik_variants` — Kovarik's pass counts and per-pass leftover against
every simulated plotter variant (:func:`orientviz.reproduce.kovarik_misses.variants`).
"""

from __future__ import annotations

from ..reproduce.kovarik_misses import PAPER_RELIEFS, needed_leftover
from .style import figure


def plot_kovarik_variants(results: dict, paper: dict, *, fig=None):
    """Pass counts and the error a pass leaves, paper against simulated plotter variants.

    Parameters
    ----------
    results : dict
        :func:`orientviz.reproduce.kovarik_misses.variants`.
    paper : dict
        :func:`orientviz.reproduce.kovarik.paper_values`.
    fig : matplotlib Figure, optional

    Returns
    -------
    matplotlib.figure.Figure
        Left: mean passes per relief (paper: bars over the printed ranges). Right: the
        ratio of the 2nd to the 1st pass's correction (log scale; paper: what its pass
        counts imply per relief, and the band its 2nd-pass scheme implies).
    """

    if fig is None:
        fig = figure(figsize=(7.0, 4.6))
    ax1, ax2 = fig.subplots(1, 2)
    styles = ["-", "--", "-.", ":"]
    for i, (name, r) in enumerate(results.items()):
        kw = (
            dict(lw=2.4, color="k")
            if i == 0
            else dict(lw=1.1, ls=styles[i % 4], color=f"C{i % 10}")
        )
        ax1.plot(100 * r.reliefs, r.passes, marker="o", ms=3, label=name, **kw)
        ax2.plot(100 * r.reliefs, r.leftover, marker="o", ms=3, **kw)
    need = needed_leftover(paper)
    for rel in PAPER_RELIEFS:
        ends = [float(x) for x in paper[f"relief|{rel:.0%}|passes"].split("-")]
        x = 100 * rel
        ax1.plot([x, x], [min(ends) - 0.5, max(ends) + 0.49], color="C3", lw=7, alpha=0.45,
                 solid_capstyle="butt")  # fmt: skip
        lo, hi = need[f"relief {rel:.0%}"]
        ax2.plot([x, x], [max(lo, 0.01), hi], color="C3", lw=7, alpha=0.45,
                 solid_capstyle="butt")  # fmt: skip
    ax1.plot([], [], color="C3", lw=7, alpha=0.45,
             label="Kovarik: printed passes ±½ / the leftover they imply")  # fmt: skip
    lo2, hi2 = need["pass 2"]
    ax2.axhspan(lo2, hi2, color="C3", alpha=0.12)
    ax2.annotate("band: the paper's 2nd pass,\n10-30 c after 100-150 c", (4.8, 0.55),
                 fontsize=9, color="C3", va="center")  # fmt: skip
    ax1.set_xlabel("relative relief [%]", fontsize=10)
    ax1.set_ylabel("passes (mean of the trials)", fontsize=10)
    ax2.set_xlabel("relative relief [%]", fontsize=10)
    ax2.set_ylabel("2nd / 1st pass correction", fontsize=10)
    ax2.set_yscale("log")
    ax2.set_ylim(0.01, 1.0)
    for ax in (ax1, ax2):
        ax.set_xlim(4.5, 16.5)
        ax.tick_params(labelsize=9)
        ax.grid(alpha=0.3)
    ax1.set_title("passes to the end point", fontsize=11)
    ax2.set_title("error a pass leaves", fontsize=11)
    fig.legend(*ax1.get_legend_handles_labels(), loc="lower center", ncol=2, fontsize=8,
               frameon=False)  # fmt: skip
    fig.tight_layout(rect=(0, 0.33, 1, 1))
    return fig
