"""Figures of gross-error detection: normalised residuals, the cleaning log, reliability.

All take results of :mod:`orientviz.adjust.gross` (or an
:class:`~orientviz.adjust.result.Adjustment`), accept ``ax=None`` and return a Figure.
"""

from __future__ import annotations

import numpy as np

from ..block import block_layout
from ..errors import InputError
from .style import subplots


def _axes(ax, **kw):

    if ax is None:
        return subplots(**kw)
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
    ax.legend(fontsize=10)
    ax.set_title(title or f"{n_out} beyond ±{critical:.2f}", fontsize=10)
    return fig


def plot_cleaning(cleaning, *, truth=None, ax=None, title=None):
    """The decisions of a cleaning run: abs(w) of each eliminated observation by adjustment.

    Parameters
    ----------
    cleaning : Cleaning
        Result of :func:`~orientviz.adjust.snooping.data_snooping`,
        :func:`~orientviz.adjust.robust.robust_adjust` or
        :func:`~orientviz.adjust.robust.rerun_cleaning`.
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
        subset = getattr(cleaning.adjustment, "subset", None)  # a bundle_solver round
        kept = subset.kept_rays if subset is not None else None
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
    ax.legend(fontsize=10)
    default = f"{cleaning.method}: {len(el)} eliminated in {cleaning.adjustments} adjustments" + (
        f", {missed} missed" if truth is not None else ""
    )
    ax.set_title(title or default, fontsize=10)
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
        fontsize=10,
    )
    return fig


# ------------------------------------------------------------------ reliability of a block
_QUANTITIES = {
    # name: (RayReliability field, per-point reduction, display factor, label)
    "mdb": ("mdb_weak", 1000.0, "largest MDB of the point's rays, weakest direction [µm]"),
    "shift": ("point_shift_max", 100.0, "largest shift of the point by an undetected MDB [cm]"),
}


def plot_reliability_map(
    rel, block, *, xyz=None, quantity: str = "mdb", ax=None, layout: bool = True, title=None
):
    """Plan of a block with its points coloured by the reliability of their rays.

    Each point gets the worst value over its adjusted rays; points with a ray whose
    2×2 redundancy block is singular (a tie point in two images: an error along the
    base leaves no residual) are drawn as red crosses, points without adjusted rays
    (check points) as grey dots.

    Parameters
    ----------
    rel : RayReliability
        From :func:`orientviz.bundle.ray_reliability`.
    block : Block
        The adjusted block (footprints from ``images.strip``; point positions).
    xyz : array_like, shape (p, 3), optional
        Point coordinates in m (e.g. ``adj["points"]``); default ``block.points.xyz``.
    quantity : {"mdb", "shift"}
        ``"mdb"``: minimal detectable bias along the weakest direction (µm);
        ``"shift"``: largest shift of the point by an undetected bias of that size (cm).
    ax : matplotlib Axes, optional
    layout : bool
        Draw the image footprints and projection centres of the strips underneath.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    if quantity not in _QUANTITIES:
        raise InputError(f"unknown quantity {quantity!r}; expected one of {sorted(_QUANTITIES)}")
    field, factor, label = _QUANTITIES[quantity]
    fig, ax = _axes(ax, figsize=(8, 5))
    p = block.n_points
    xy = np.asarray(block.points.xyz if xyz is None else xyz, float).reshape(-1, 3)[:, :2]
    if layout:
        from matplotlib.patches import Polygon

        lay = block_layout(block)
        for k, imgs in enumerate(lay.strips):
            for i in imgs:
                ax.add_patch(
                    Polygon(lay.footprints[i], closed=True, fill=False, ec="#b0b7bf", lw=0.5)
                )
            X0 = block.images.X0[imgs]
            ax.plot(
                X0[:, 0],
                X0[:, 1],
                "^",
                color="#34495e",
                ms=5,
                zorder=2,
                label="projection centres" if k == 0 else None,
            )
    value = rel.by_point(getattr(rel, field), p) * factor
    blind = rel.by_point(np.where(rel.used, ~rel.testable, np.nan).astype(float), p) > 0
    unused = np.isnan(value)
    ok = ~unused & ~blind
    sc = ax.scatter(xy[ok, 0], xy[ok, 1], c=value[ok], cmap="plasma", s=22, zorder=3)
    fig.colorbar(sc, ax=ax, label=label, shrink=0.85)
    ax.scatter(
        xy[blind, 0], xy[blind, 1], marker="x", color="#c0392b", s=22, lw=1.2, zorder=3,
        label=f"not testable along the base ({int(blind.sum())} points)",
    )  # fmt: skip
    if unused.any():
        ax.scatter(
            xy[unused, 0],
            xy[unused, 1],
            color="#95a5a6",
            s=8,
            zorder=2,
            label="not adjusted (check points)",
        )
    ctrl = (block.points.role == 1) & ~unused
    ax.scatter(
        xy[ctrl, 0], xy[ctrl, 1], marker="s", s=70, facecolor="none", edgecolor="k", lw=0.8,
        zorder=4, label="control",
    )  # fmt: skip
    ax.set_aspect("equal")
    ax.set_xlabel("X [m]")
    ax.set_ylabel("Y [m]")
    ax.legend(fontsize=10, loc="upper left", bbox_to_anchor=(0.0, -0.12), ncol=1, frameon=False)
    ax.set_title(
        title
        or f"reliability of the rays (α0 = {rel.alpha0:g}, β0 = {rel.beta0:g}, δ0 = "
        f"{rel.delta0:.2f})",
        fontsize=10,
    )
    return fig


def plot_mdb_histogram(rel, block, *, ax=None, title=None):
    """Histogram of the rays' MDB along their weakest direction (µm), by rays per point.

    Parameters
    ----------
    rel : RayReliability
        From :func:`orientviz.bundle.ray_reliability`.
    block : Block
        The adjusted block (for the number of rays per point).
    ax : matplotlib Axes, optional
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = _axes(ax, figsize=(5, 3.5))
    k = block.rays_per_point()[rel.point]
    ok = rel.used & rel.testable
    mdb = rel.mdb_weak * 1000.0
    groups = [
        ("2 rays (control)", k == 2),
        ("3 rays", k == 3),
        ("4-5 rays", (k >= 4) & (k <= 5)),
        ("6+ rays", k >= 6),
    ]
    data = [mdb[ok & g] for _, g in groups]
    labels = [f"{name}: {d.size}" for (name, _), d in zip(groups, data)]
    keep = [i for i, d in enumerate(data) if d.size]
    hi = float(np.max(mdb[ok], initial=1.0))
    ax.hist([data[i] for i in keep], bins=np.linspace(0.0, hi * 1.02, 40), stacked=True,
            label=[labels[i] for i in keep], color=[("#34495e", "#e67e22", "#27ae60", "#2980b9")[i] for i in keep])  # fmt: skip
    blind = int((rel.used & ~rel.testable).sum())
    ax.set_xlabel("MDB along the weakest direction [µm]")
    ax.set_ylabel("rays")
    ax.legend(fontsize=10, title="testable rays of points with", title_fontsize=10)
    ax.set_title(
        title or f"{int(ok.sum())} testable rays; {blind} not testable (MDB infinite)", fontsize=10
    )
    return fig


def plot_block_reliability(rel, block, *, xyz=None, quantity: str = "mdb", title=None):
    """The reliability map of a block above the MDB histogram of its rays (book column width).

    Parameters
    ----------
    rel : RayReliability
    block : Block
    xyz : array_like, shape (p, 3), optional
        Point coordinates in m (default ``block.points.xyz``).
    quantity : {"mdb", "shift"}
        What colours the map (see :func:`plot_reliability_map`).
    title : str, optional
        Title of the figure.

    Returns
    -------
    matplotlib.figure.Figure
    """

    fig, (a1, a2) = subplots(2, 1, figsize=(8.5, 10), height_ratios=[1.6, 1], layout="constrained")
    plot_reliability_map(rel, block, xyz=xyz, quantity=quantity, ax=a1)
    plot_mdb_histogram(rel, block, ax=a2)
    if title:
        fig.suptitle(title, fontsize=10)
    return fig
