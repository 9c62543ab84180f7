"""Figures of aerotriangulation blocks: layout, error vectors, ellipses, precision laws.

Object frame in m (X along the strips, Y across, Z up); planimetric figures look down
on the XY plane. All functions take results, draw into ``ax`` (a new figure if None) and
return the Figure; matplotlib is imported only inside them.
"""

from __future__ import annotations

import numpy as np

from ..block import CHECK, CONTROL, block_layout
from ..simulate import check_differences, fit_log_law
from .style import subplots

#: Colours of control kinds and roles.
COLORS = {"xyz": "#c0392b", "xy": "#2471a3", "z": "#27ae60", "check": "#8e44ad", "tie": "0.55"}


def _axes(ax, figsize=(7, 5)):

    if ax is None:
        fig, ax = subplots(figsize=figsize)
        return fig, ax
    return ax.figure, ax


def _block_and_layout(obj):
    block = getattr(obj, "truth", obj)
    layout = getattr(obj, "layout", None) or block_layout(block)
    return block, layout


def plot_block_layout(obj, *, ax=None, show_footprints: bool = True, show_models: bool = True,
                      show_ties: bool = True, title: str | None = None):  # fmt: skip
    """Plan of a block: image footprints by strip, models, projection centres, control.

    Parameters
    ----------
    obj : SimulatedBlock or Block
        A simulated block (its truth is drawn) or any block with ``images.strip``.
    ax : matplotlib Axes, optional
    show_footprints, show_models, show_ties : bool
        Draw the image footprints, the model areas (overlap of the two images, hatched
        every other model) and the tie points.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt
    from matplotlib.patches import Polygon

    block, lay = _block_and_layout(obj)
    fig, ax = _axes(ax, figsize=(8, 6))
    cmap = plt.get_cmap("tab10")
    for k, imgs in enumerate(lay.strips):
        col = cmap(k % 10)
        if show_footprints:
            for i in imgs:
                ax.add_patch(
                    Polygon(lay.footprints[i], closed=True, fill=False, ec=col, lw=0.5, alpha=0.5)
                )
        X0 = block.images.X0[imgs]
        ax.plot(X0[:, 0], X0[:, 1], "-", color=col, lw=1.0, alpha=0.8)
        ax.plot(X0[:, 0], X0[:, 1], "^", color=col, ms=4, label=f"strip {k}" if k < 6 else None)
    if show_models:
        for n, (a, b) in enumerate(lay.models):
            fa, fb = lay.footprints[a], lay.footprints[b]
            lo = np.maximum(fa.min(axis=0), fb.min(axis=0))
            hi = np.minimum(fa.max(axis=0), fb.max(axis=0))
            if np.all(hi > lo):
                rect = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
                ax.add_patch(
                    Polygon(rect, closed=True, fc="0.85" if n % 2 else "0.93", ec="none", zorder=0)
                )
    p = block.points
    if show_ties:
        tie = p.role == 0
        ax.plot(p.xyz[tie, 0], p.xyz[tie, 1], ".", color=COLORS["tie"], ms=2, label="tie points")
    ctrl = p.role == CONTROL
    given = ~np.isnan(p.xyz_known)
    for kind, mask, marker in (
        ("xyz", ctrl & given.all(axis=1), "s"),
        ("xy", ctrl & given[:, 0] & ~given[:, 2], "o"),
        ("z", ctrl & ~given[:, 0] & given[:, 2], "D"),
        ("check", p.role == CHECK, "x"),
    ):
        if np.any(mask):
            label = {
                "xyz": "XYZ control",
                "xy": "XY control",
                "z": "Z control",
                "check": "check points",
            }[kind]
            ax.plot(
                p.xyz[mask, 0],
                p.xyz[mask, 1],
                marker,
                color=COLORS[kind],
                ms=6,
                mfc="none" if kind != "xyz" else COLORS[kind],
                label=label,
            )
    ax.set_aspect("equal")
    ax.set_xlabel("X [m]")
    ax.set_ylabel("Y [m]")
    ax.legend(fontsize=10, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ns = len(lay.strips)
    ax.set_title(
        title or f"{ns} strips, {block.n_images} images, {lay.n_models} models", fontsize=10
    )
    fig.tight_layout()
    return fig


def plot_error_vectors(xyz, reference, *, ax=None, exaggeration: float | None = None,
                       control=None, zlim: float | None = None, title: str | None = None):  # fmt: skip
    """Planimetric error vectors (arrows) and height errors (colour) of points.

    Parameters
    ----------
    xyz, reference : array_like, shape (p, 3)
        Estimated and reference (e.g. true, or another method's) coordinates in m; rows
        with NaN are skipped.
    ax : matplotlib Axes, optional
    exaggeration : float, optional
        Arrow exaggeration (default: the largest arrow is 1/15 of the block width).
    control : array_like of bool, shape (p,), optional
        Points drawn as control (squares) instead of arrows.
    zlim : float, optional
        Colour range ±zlim (m) of the height errors (default: the largest); give the same
        ``zlim`` and ``exaggeration`` to compare figures side by side.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    xyz, ref = np.asarray(xyz, float), np.asarray(reference, float)
    ok = np.all(np.isfinite(xyz), axis=1) & np.all(np.isfinite(ref), axis=1)
    ctrl = np.zeros(len(xyz), bool) if control is None else np.asarray(control, bool)
    d = xyz - ref
    fig, ax = _axes(ax, figsize=(8, 6))
    sel = ok & ~ctrl
    width = float(np.ptp(ref[ok, 0])) or 1.0
    big = max(float(np.max(np.hypot(d[sel, 0], d[sel, 1]), initial=0.0)), 1e-12)
    ex = exaggeration if exaggeration is not None else width / 15.0 / big
    lim = float(zlim) if zlim is not None else float(np.max(np.abs(d[sel, 2]), initial=1e-12))
    sc = ax.scatter(
        ref[sel, 0], ref[sel, 1], c=d[sel, 2], cmap="RdBu_r", vmin=-lim, vmax=lim, s=14, zorder=3
    )
    ax.quiver(ref[sel, 0], ref[sel, 1], ex * d[sel, 0], ex * d[sel, 1], angles="xy",
              scale_units="xy", scale=1.0, width=0.003, color="k", zorder=4)  # fmt: skip
    if np.any(ctrl & ok):
        ax.plot(
            ref[ctrl & ok, 0], ref[ctrl & ok, 1], "s", color=COLORS["xyz"], ms=6, label="control"
        )
        ax.legend(fontsize=10)
    fig.colorbar(sc, ax=ax, label="ΔZ [m]", shrink=0.8)
    rms = np.sqrt(np.mean(d[sel] ** 2, axis=0)) if np.any(sel) else np.zeros(3)
    ax.set_aspect("equal")
    ax.set_xlabel("X [m]")
    ax.set_ylabel("Y [m]")
    ax.set_title(
        title
        or f"errors: RMS X {rms[0]:.3f} m, Y {rms[1]:.3f} m, Z {rms[2]:.3f} m; arrows ×{ex:.0f}",
        fontsize=10,
    )
    fig.tight_layout()
    return fig


def plot_error_ellipses(xy, cov, *, ax=None, scale: float | None = None, control_xy=None,
                        every: int = 1, title: str | None = None):  # fmt: skip
    """Standard error ellipses of points in planimetry.

    Parameters
    ----------
    xy : array_like, shape (p, 2)
        Point positions in m.
    cov : array_like, shape (p, 2, 2) or (p, 3, 3)
        Covariance matrices in m² (the XY block is used).
    ax : matplotlib Axes, optional
    scale : float, optional
        Ellipse exaggeration (default: the largest semi-axis drawn as 1/100 of the width).
    control_xy : array_like, shape (k, 2), optional
        Control points to mark.
    every : int
        Draw every n-th ellipse (for large blocks).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.collections import EllipseCollection

    xy = np.asarray(xy, float)[::every, :2]
    C = np.asarray(cov, float)[::every, :2, :2]
    w, V = np.linalg.eigh(C)
    a, b = np.sqrt(np.clip(w[:, 1], 0, None)), np.sqrt(np.clip(w[:, 0], 0, None))
    ang = np.degrees(np.arctan2(V[:, 1, 1], V[:, 0, 1]))
    fig, ax = _axes(ax, figsize=(8, 6))
    width = float(np.ptp(xy[:, 0])) or 1.0
    s = scale if scale is not None else width / 100.0 / max(float(a.max(initial=0.0)), 1e-12)
    ec = EllipseCollection(2 * s * a, 2 * s * b, ang, units="xy", offsets=xy, offset_transform=ax.transData,
                           facecolors="none", edgecolors="#1f4e79", linewidths=0.8)  # fmt: skip
    ax.add_collection(ec)
    ax.plot(xy[:, 0], xy[:, 1], ".", color="0.4", ms=1.5)
    if control_xy is not None and len(control_xy):
        c = np.asarray(control_xy, float)
        ax.plot(c[:, 0], c[:, 1], "s", color=COLORS["xyz"], ms=5, label="control")
        ax.legend(fontsize=10)
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("X [m]")
    ax.set_ylabel("Y [m]")
    ax.set_title(
        title or f"standard error ellipses ×{s:.0f} (largest semi-axis {a.max(initial=0):.3f} m)",
        fontsize=10,
    )
    fig.tight_layout()
    return fig


def plot_precision_map(prec, *, ax=None, title: str | None = None):
    """Map of the standard deviations of a :class:`~orientviz.simulate.BlockPrecision`.

    Planimetry: colour = √((σ_X² + σ_Y²)/2)/σ0; height: σ_Z/σ0; control marked.

    Returns
    -------
    matplotlib.figure.Figure
    """
    sd = np.asarray(prec.sd, float)
    val = np.sqrt(np.mean(sd**2, axis=1)) if sd.ndim == 2 else sd
    fig, ax = _axes(ax, figsize=(8, 5))
    sc = ax.scatter(prec.xy[:, 0], prec.xy[:, 1], c=val, cmap="viridis", s=18)
    if len(prec.control_xy):
        ax.plot(
            prec.control_xy[:, 0],
            prec.control_xy[:, 1],
            "s",
            color=COLORS["xyz"],
            ms=5,
            mfc="none",
            label="control",
        )
        ax.legend(fontsize=10, loc="upper right")
    lab = "σ_xy / σ0" if prec.kind == "planimetry" else "σ_z / σ0"
    fig.colorbar(sc, ax=ax, label=lab, shrink=0.8)
    ax.set_aspect("equal")
    ax.set_xlabel("X [m]")
    ax.set_ylabel("Y [m]")
    what = (
        f"perimeter every {prec.spacing} b"
        if prec.kind == "planimetry"
        else f"height chains every i = {prec.spacing} b"
    )
    ax.set_title(
        title
        or f"{prec.kind}: {prec.n_strips} strips, {prec.n_models} models, {what}; μ = {prec.mu:.2f} σ0",
        fontsize=10,
    )
    fig.tight_layout()
    return fig


def plot_strip_law(precisions, *, ax=None, fit: bool = True, title: str | None = None):
    """μ_xy/σ0 against the number of strips (log axis) — Ackermann's Bild 3 after Ebner.

    Parameters
    ----------
    precisions : list of BlockPrecision
        Planimetric results, possibly for several control spacings.
    fit : bool
        Draw the fitted law μ = a + b·log10(n_s) per spacing.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = _axes(ax, figsize=(6, 4))
    for k in sorted({p.spacing for p in precisions}):
        ps = sorted((p for p in precisions if p.spacing == k), key=lambda p: p.n_strips)
        ns = np.array([p.n_strips for p in ps])
        mu = np.array([p.mu for p in ps])
        (line,) = ax.plot(ns, mu, "o-", label=f"μ_xy, perimeter every {k} b")
        emp = [(p.n_strips, p.empirical) for p in ps if p.empirical is not None]
        if emp:
            e = np.array(emp)
            ax.plot(e[:, 0], e[:, 1], "x", color=line.get_color(), ms=8, label="simulated")
        if fit and len(ns) >= 2:
            a, b = fit_log_law(ns, mu)
            xs = np.geomspace(ns.min(), ns.max(), 50)
            ax.plot(
                xs,
                a + b * np.log10(xs),
                ":",
                color=line.get_color(),
                label=f"{a:.2f} + {b:.2f}·log10 n_s",
            )
    ax.axhline(2.0, color="0.4", ls="--", lw=0.8, label="Ackermann: μ_xy < 2 σ0")
    from matplotlib.ticker import NullFormatter, ScalarFormatter

    ax.set_xscale("log")
    ticks = sorted({p.n_strips for p in precisions})
    ax.set_xticks(ticks)
    ax.xaxis.set_major_formatter(ScalarFormatter())
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("number of strips n_s (square block)")
    ax.set_ylabel("μ_xy / σ0")
    ax.set_ylim(0, 2.2)
    ax.legend(fontsize=10, loc="lower right", ncol=2)
    ax.set_title(title or "planimetric precision of independent-model blocks", fontsize=10)
    fig.tight_layout()
    return fig


def plot_height_law(precisions, *, ax=None, title: str | None = None):
    """μ_z/σ0 and σ_z,max/σ0 against the chain spacing i — Ackermann's Bild 4 after Ebner.

    Returns
    -------
    matplotlib.figure.Figure
    """
    ps = sorted(precisions, key=lambda p: p.spacing)
    i = np.array([p.spacing for p in ps])
    fig, ax = _axes(ax, figsize=(6, 4))
    ax.plot(i, [p.mu for p in ps], "o-", label="μ_z / σ0")
    ax.plot(i, [p.max for p in ps], "s--", label="σ_z,max / σ0")
    emp = [(p.spacing, p.empirical) for p in ps if p.empirical is not None]
    if emp:
        e = np.array(emp)
        ax.plot(e[:, 0], e[:, 1], "x", color="k", ms=8, label="simulated μ_z")
    ax.axhline(1.0, color="0.4", ls=":", lw=0.8, label="single model (σ0)")
    ax.set_xlabel("spacing i of the height-control chains [bases]")
    ax.set_ylabel("σ / σ0")
    ax.legend(fontsize=10)
    ax.set_title(title or "height precision of independent-model blocks", fontsize=10)
    fig.tight_layout()
    return fig


def plot_check_heights(sim, results, *, ax=None, title: str | None = None):
    """Height errors of the check points along the strips, one marker series per result.

    Each result's check points are compared with the truth of the simulated block
    (:func:`orientviz.simulate.check_differences`) and drawn at their true X:
    strip bending between sparse height control shows as a wave along X.

    Parameters
    ----------
    sim : SimulatedBlock
        The simulated block (:func:`orientviz.simulate.simulate_block`); X is
        taken from its truth (m, drawn in km).
    results : mapping of str to Adjustment or ndarray (p, 3)
        Label → bundle or independent-model adjustment of the block, or adjusted
        coordinates of all points in m.
    ax : matplotlib Axes, optional
        Axes to draw into; a new figure if None.
    title : str, optional
        Title (default: "height errors at the check points").

    Returns
    -------
    matplotlib.figure.Figure
        ΔZ (adjusted − true) in m against X in km; the legend gives each result's
        μz (RMS ΔZ) in m.
    """
    fig, ax = _axes(ax, figsize=(8, 3.5))
    markers = "os^Dvx+"
    for k, (label, result) in enumerate(dict(results).items()):
        idx, d = check_differences(sim, result)
        x = sim.truth.points.xyz[idx, 0] / 1000.0
        mu_z = float(np.sqrt(np.mean(d[:, 2] ** 2)))
        ax.plot(x, d[:, 2], markers[k % len(markers)], ms=5, label=f"{label} (μz {mu_z:.2f} m)")
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xlabel("X along the strips [km]")
    ax.set_ylabel("ΔZ at check points [m]")
    ax.legend(fontsize=10)
    ax.set_title(title or "height errors at the check points", fontsize=10)
    fig.tight_layout()
    return fig
