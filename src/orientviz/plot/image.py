"""Image-plane figures: projected points and wireframes, residual vectors.

Image coordinates in mm in the fiducial frame (x right, y up, seen from the projection
centre — the positive, see :mod:`orientviz.camera`). Residuals follow the engine's sign
``v = f(x̂) − l``: the arrow points from the measured to the adjusted image position.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .style import subplots


def plot_image(
    xy: ArrayLike,
    *,
    edges: ArrayLike | None = None,
    residuals: ArrayLike | None = None,
    scale: float | None = None,
    format_mm: tuple[float, float] = (230.0, 230.0),
    labels: list[str] | None = None,
    ax=None,
    title: str | None = None,
    color: str = "k",
):
    """Image points (and optional wireframe and residual vectors) in the image frame.

    Parameters
    ----------
    xy : array_like, shape (n, 2)
        Image coordinates in mm.
    edges : array_like of int, shape (k, 2), optional
        Index pairs of points to join by lines (a house, a grid).
    residuals : array_like, shape (n, 2), optional
        Residuals in mm (``v = f(x̂) − l``), drawn as arrows ``scale`` times enlarged.
    scale : float, optional
        Exaggeration of the residual arrows; default so that the largest spans 8 % of
        the format (~18 mm on a 230 mm image).
    format_mm : tuple of float, default (230, 230)
        Image format drawn as the frame, mm.
    labels : list of str, optional
        A label per point.
    ax : matplotlib.axes.Axes, optional
    title : str, optional
    color : str, default "k"

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    if ax is None:
        _, ax = subplots(figsize=(5, 5))
    fig = ax.figure
    w, h = format_mm[0] / 2, format_mm[1] / 2
    ax.add_patch(plt.Rectangle((-w, -h), 2 * w, 2 * h, fill=False, color="0.5", lw=1))
    if edges is not None:
        e = np.asarray(edges, dtype=int).reshape(-1, 2)
        segs = np.stack([xy[e[:, 0]], xy[e[:, 1]]], axis=1)
        from matplotlib.collections import LineCollection

        ax.add_collection(LineCollection(segs, colors=color, linewidths=1.2))
    ax.plot(xy[:, 0], xy[:, 1], "o", color=color, ms=3)
    if residuals is not None:
        v = np.asarray(residuals, dtype=float).reshape(-1, 2)
        vmax = float(np.nanmax(np.linalg.norm(v, axis=1))) if v.size else 0.0
        if scale is None:
            scale = 0.08 * max(format_mm) / vmax if vmax > 0 else 1.0
        ax.quiver(
            xy[:, 0], xy[:, 1], v[:, 0] * scale, v[:, 1] * scale,
            angles="xy", scale_units="xy", scale=1.0, color="#c0392b", width=0.004,
        )  # fmt: skip
        ax.text(
            0.02, 0.98, f"residuals × {scale:.3g} (largest {vmax * 1000:.1f} µm)",
            transform=ax.transAxes, fontsize=8, color="#c0392b", va="top",
        )  # fmt: skip
    if labels is not None:
        for (x, y), lab in zip(xy, labels):
            ax.text(x + 2, y + 2, str(lab), fontsize=8)
    pad = 0.05 * max(w, h)
    ax.set_xlim(-w - pad, w + pad)
    ax.set_ylim(-h - pad, h + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    if title:
        ax.set_title(title, fontsize=10)
    return fig


def plot_correlations(result, *, names: list[str] | None = None, ax=None, annotate: bool = True):
    """Correlation matrix of an :class:`~orientviz.adjust.Adjustment` as a heat map.

    Parameters
    ----------
    result : Adjustment
        With a dense cofactor matrix.
    names : list of str, optional
        Subset (and order) of parameter names; default all.
    ax : matplotlib.axes.Axes, optional
    annotate : bool, default True
        Write ρ into each cell.

    Returns
    -------
    matplotlib.figure.Figure
    """

    names = list(result.names) if names is None else list(names)
    idx = [result.index(n) for n in names]
    C = result.correlations()[np.ix_(idx, idx)]
    if ax is None:
        _, ax = subplots(figsize=(0.6 * len(names) + 2, 0.6 * len(names) + 1.5))
    fig = ax.figure
    im = ax.imshow(C, cmap="RdBu_r", vmin=-1, vmax=1)
    ax.set_xticks(range(len(names)), names, rotation=45, ha="right")
    ax.set_yticks(range(len(names)), names)
    if annotate:
        for i in range(len(names)):
            for j in range(len(names)):
                ax.text(j, i, f"{C[i, j]:.2f}", ha="center", va="center", fontsize=8,
                        color="white" if abs(C[i, j]) > 0.6 else "black")  # fmt: skip
    fig.colorbar(im, ax=ax, shrink=0.8, label="correlation ρ")
    return fig
