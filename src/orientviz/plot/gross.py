"""Figures of gross-error detection: normalised residuals, the cleaning log, reliability.

All take results of :mod:`orientviz.adjust.gross` (or an
:class:`~orientviz.adjust.result.Adjustment`), accept ``ax=None`` and return a Figure.
"""

from __future__ import annotations

import numpy as np


def _axes(ax, **kw):
    import matplotlib.pyplot as plt

    if ax is None:
        return plt.subplots(**kw)
    return ax.figure, ax


def plot_normalized_residuals(adj, *, critical: float = 3.29, ax=None, title=None):
    """Histogram of the normalised residuals w_i with N(0, 1) and the critical value ±k.

    Parameters
    ----------
    adj : Adjustment
        With ``normalized_residuals`` (NaN entries, e.g. eliminated ones, are skipped).
    critical : float
        Critical value k of the w-test (3.29 for α0 = 0.1 %).
    ax : matplotlib Axes, optional
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = _axes(ax, figsize=(6, 3.5))
    w = np.asarray(adj.normalized_residuals, float)
    w = w[np.isfinite(w)]
    lim = max(float(np.max(np.abs(w), initial=0.0)), critical + 1.0)
    bins = np.linspace(-lim, lim, 61)
    ax.hist(w, bins=bins, color="#5d6d7e", alpha=0.8, label=f"{w.size} residuals")
    t = np.linspace(-lim, lim, 400)
    ax.plot(
        t,
        w.size * (bins[1] - bins[0]) * np.exp(-0.5 * t * t) / np.sqrt(2 * np.pi),
        color="k",
        lw=1,
        label="N(0, 1)",
    )
    for s in (-critical, critical):
        ax.axvline(s, color="#c0392b", ls="--", lw=1)
    n_out = int(np.sum(np.abs(w) > critical))
    ax.set_yscale("symlog", linthresh=1.0)
    ax.set_xlabel("normalised residual w = v / (σ √r)")
    ax.set_ylabel("count")
    ax.legend(fontsize=8)
    ax.set_title(title or f"{n_out} beyond ±{critical:.2f}", fontsize=9)
    return fig


def plot_cleaning(cleaning, *, truth=None, ax=None, title=None):
    """The decisions of a cleaning run: abs(w) of each eliminated observation by adjustment.

    Parameters
    ----------
    cleaning : Cleaning
        Result of :func:`~orientviz.adjust.gross.data_snooping`,
        :func:`~orientviz.adjust.gross.robust_adjust` or
        :func:`~orientviz.adjust.gross.rerun_cleaning`.
    truth : array_like of int, optional
        The truly corrupted observations (groups): eliminations are coloured as correct
        (in ``truth``) or false alarms; the missed ones are listed in the title.
    ax : matplotlib Axes, optional
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = _axes(ax, figsize=(6, 3.5))
    el = [e for e in cleaning.log if e.action == "eliminated"]
    it = np.array([e.iteration for e in el], float)
    w = np.array([e.w for e in el], float)
    obs = np.array([e.observation for e in el], int)
    good = np.ones(len(el), bool)
    missed = 0
    if truth is not None:
        tr = set(np.asarray(truth, int).tolist())
        good = np.array([o in tr for o in obs], bool)
        gone = set(obs.tolist())
        kept = cleaning.adjustment.extra.get("kept_rays")
        if kept is not None:  # rays left out with their point count as removed too
            gone |= set(np.flatnonzero(~np.asarray(kept, bool)).tolist())
        missed = len(tr - gone)
    if len(el):
        ax.scatter(it[good], w[good], color="#27ae60", label="gross error found", zorder=3)
        if (~good).any():
            ax.scatter(it[~good], w[~good], color="#c0392b", marker="x", label="false alarm")
    ax.set_yscale("log")
    from matplotlib.ticker import MaxNLocator

    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("adjustment" if cleaning.method != "reruns" else "rerun")
    ax.set_ylabel("|w| (test statistic) at elimination")
    ax.legend(fontsize=8)
    default = f"{cleaning.method}: {len(el)} eliminated in {cleaning.adjustments} adjustments" + (
        f", {missed} missed" if truth is not None else ""
    )
    ax.set_title(title or default, fontsize=9)
    return fig


def plot_reliability(rel, *, ax=None, sigma_unit: float = 1.0, unit: str = "", title=None):
    """Redundancy numbers and minimal detectable biases of all observations.

    Parameters
    ----------
    rel : Reliability
        From :func:`~orientviz.adjust.gross.reliability`.
    ax : matplotlib Axes, optional
    sigma_unit : float
        Factor applied to the MDB for display (e.g. 1000 to show mm as µm).
    unit : str
        Unit label of the displayed MDB.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = _axes(ax, figsize=(6, 3.5))
    r = rel.redundancy_numbers
    ok = np.isfinite(rel.mdb)
    sc = ax.scatter(r[ok], rel.mdb[ok] * sigma_unit, c=rel.external[ok], cmap="viridis", s=10)
    fig.colorbar(sc, ax=ax, label="external reliability δ̄0")
    ax.set_xlabel("redundancy number r_i")
    ax.set_ylabel(f"minimal detectable bias ∇_i {unit}".strip())
    ax.set_xlim(0, 1)
    ax.set_title(
        title
        or f"α0 = {rel.alpha0:g}, β0 = {rel.beta0:g}: δ0 = {rel.delta0:.2f}; "
        f"{int((~ok).sum())} uncontrolled",
        fontsize=9,
    )
    return fig
