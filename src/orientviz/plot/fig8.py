"""Geier's Fig. 8 against the package's rounding distribution (pure figure functions).

:func:`plot_rounding_distribution` draws, for the quantities of one task and the ten
surfaces, the spread of the package's values over many rounding draws
(:func:`orientviz.radar.rounding.rounding_draws`) as a box (middle 50 %) with whiskers
(5-95 %), the package's own value for the paper's rounding as a black dash, and the
paper's printed value as a red dot. :func:`plot_positions` shows, per task, where the
printed values lie in that distribution (in standard deviations). matplotlib is
imported lazily.
"""

from __future__ import annotations

import numpy as np

from ..radar.fig8 import UNITS
from .style import figure, subplots

_SHORT = {
    "fig7": "Fig.7", "plane": "plane", "sphere150_convex": "sph150∩",
    "cyl_y150_convex": "cy150∩", "cyl_x150_convex": "cx150∩", "sphere150_concave": "sph150∪",
    "cyl_y150_concave": "cy150∪", "cyl_x150_concave": "cx150∪", "sphere300_concave": "sph300∪",
    "cyl_x300_concave": "cx300∪",
}  # fmt: skip
_TASK = {
    "trilateration": "2a trilat.", "rotations": "2b rotations", "exterior": "2c exterior\n(fitted)",
    "relative_near_normal": "4a relative\n1-2", "all_ten": "3 all ten", "calibration":
    "1 calibration\n(fitted)", "relative_general": "4a relative\n1-3",
}  # fmt: skip
_CLIP = 12.0


def plot_rounding_distribution(dist, paper: dict, task: str, *, quantities=None, fig=None):
    """Paper values against the package's distribution over rounding draws, one task.

    Parameters
    ----------
    dist : orientviz.radar.rounding.RoundingDraws
    paper : dict
        The Fig. 8 table (:func:`orientviz.radar.data.load_fig8_paper`).
    task : str
        One of ``dist.tasks``.
    quantities : sequence of str, optional
        Which quantities (default: all of the task except the correlations).
    fig : matplotlib Figure, optional

    Returns
    -------
    matplotlib.figure.Figure
        One panel per quantity, the ten surfaces along x, values in the paper's units.
    """

    qs = [q for q in (quantities or dist.draws[task]) if not q.startswith("r_")]
    n = len(qs)
    ncol = 2 if n > 3 else 1
    nrow = int(np.ceil(n / ncol))
    if fig is None:
        fig = figure(figsize=(7.0, 1.9 * nrow + 0.6))
    axes = fig.subplots(nrow, ncol, squeeze=False, sharex=True)
    cols = list(paper["columns"])
    x = np.arange(len(dist.surfaces))
    for k, q in enumerate(qs):
        ax = axes[k // ncol][k % ncol]
        a = dist.draws[task][q]
        lo, q1, q3, hi = np.nanpercentile(a, [5, 25, 75, 95], axis=0)
        ax.vlines(x, lo, hi, color="0.6", lw=1)
        ax.bar(x, q3 - q1, bottom=q1, width=0.55, color="0.85", edgecolor="0.5", lw=0.6,
               label="orientviz, 50 % / 90 % of draws")  # fmt: skip
        ax.plot(x, dist.own[task][q], "_", color="k", ms=12, mew=1.6,
                label="orientviz, the paper's rounding")  # fmt: skip
        pv = [paper["tasks"][task][q][cols.index(s)] for s in dist.surfaces]
        p = np.array([np.nan if v is None else v for v in pv], float)
        ax.plot(x, p, "o", color="C3", ms=4.5, label="paper (Fig. 8)")
        ax.axhline(0, color="0.7", lw=0.5)
        unit = {"1e-6": "1e-6", "cc": "cc", "m": "m", "1": ""}[UNITS[q]]
        ax.set_ylabel(f"{q} [{unit}]" if unit else q, fontsize=10)
        ax.tick_params(labelsize=9)
    for k in range(n, nrow * ncol):
        axes[k // ncol][k % ncol].set_visible(False)
    for ax in axes[-1]:
        ax.set_xticks(x)
        ax.set_xticklabels([_SHORT.get(s, s) for s in dist.surfaces], rotation=60, fontsize=9)
    if n > ncol and ncol == 2 and n % 2 == 1:
        ax = axes[-2][1]
        ax.set_xticks(x)
        ax.set_xticklabels([_SHORT.get(s, s) for s in dist.surfaces], rotation=60, fontsize=9)
        ax.tick_params(labelbottom=True)
    fig.suptitle(f"Fig. 8, {task}: paper vs {dist.n_draws} rounding draws", fontsize=11)
    fig.legend(*axes[0][0].get_legend_handles_labels(), loc="upper center", ncol=3, fontsize=8,
               frameon=False, bbox_to_anchor=(0.5, 0.955))  # fmt: skip
    fig.tight_layout(rect=(0, 0, 1, 0.92))
    return fig


def plot_positions(positions: dict, *, ax=None):
    """Where the printed values lie in the package's rounding distribution, per task.

    Parameters
    ----------
    positions : dict
        From :func:`orientviz.radar.rounding.paper_position` (task → quantity → z).
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
        Every printed number as a dot at its position (in σ of the draws), the rms per
        task as a bar, and the band ±2σ that one more draw would fall in 95 % of the time.
    """

    if ax is None:
        fig, ax = subplots(figsize=(7.0, 3.8))
    else:
        fig = ax.figure
    tasks = list(positions)
    rng = np.random.default_rng(0)  # jitter of the dots only
    for i, t in enumerate(tasks):
        z = np.concatenate([np.ravel(v) for q, v in positions[t].items() if not q.startswith("r_")])
        z = z[np.isfinite(z)]
        x = i + rng.uniform(-0.25, 0.25, z.size)
        inside = np.abs(z) <= _CLIP
        ax.plot(x[inside], z[inside], ".", color="C3", ms=3, alpha=0.6)
        ax.plot(x[~inside], np.sign(z[~inside]) * (_CLIP - 0.4), "^", color="C3", ms=3)
        for sgn in (1.0, -1.0):
            n_out = int(np.sum(z * sgn > _CLIP))
            if n_out:
                ax.annotate(f"{n_out} beyond", (i, sgn * (_CLIP - 1.6)), ha="center",
                            va="center", fontsize=8, color="C3")  # fmt: skip
        rms = float(np.sqrt(np.mean(z**2))) if z.size else np.nan
        ax.hlines(rms, i - 0.35, i + 0.35, color="k", lw=2)
        ax.annotate(f"rms {rms:.1f}σ", (i, rms), xytext=(0, 4), textcoords="offset points",
                    ha="center", fontsize=9)  # fmt: skip
    ax.axhspan(-2, 2, color="C2", alpha=0.12, label="±2σ: one more rounding draw")
    ax.set_xticks(range(len(tasks)))
    ax.set_xticklabels([_TASK.get(t, t) for t in tasks], fontsize=9)
    ax.set_ylabel("(paper − mean) / σ of the draws", fontsize=10)
    ax.set_ylim(-_CLIP, _CLIP)
    ax.legend(fontsize=8, loc="lower right")
    ax.set_title("Fig. 8: where the paper's values lie in orientviz's rounding spread",
                 fontsize=11)  # fmt: skip
    fig.tight_layout()
    return fig
