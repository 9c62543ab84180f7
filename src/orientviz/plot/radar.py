"""Figures of radar panorama (PPI) images: pure functions returning a Figure.

Each function takes results or plain scene data from :mod:`orientviz.radar`, draws on
``ax`` (or a new figure) and returns the Figure. matplotlib is imported lazily.
Units: metres (object and image), angles as in the data.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .style import figure


def _axes(ax, projection: str | None = None, figsize=(6.0, 5.0)):

    if ax is not None:
        return ax.figure, ax
    fig = figure(figsize=figsize)
    return fig, fig.add_subplot(111, projection=projection)


def plot_image(
    xy: ArrayLike,
    image: Any = None,
    *,
    residuals: ArrayLike | None = None,
    scale: float = 10000.0,
    rings: int = 4,
    labels: bool = True,
    ax=None,
):
    """The PPI image: points, principal point, range rings and residual arrows.

    Parameters
    ----------
    xy : array_like, shape (n, 2)
        Image coordinates, image m.
    image : RadarImage, optional
        Draws the principal point and range rings about it.
    residuals : array_like, shape (n, 2), optional
        Image residuals (m), drawn as arrows times ``scale``.
    scale : float
        Exaggeration of the residual arrows.
    rings : int
        Number of range rings.
    labels : bool
        Number the points 1…n.
    ax : matplotlib Axes, optional
    """
    fig, ax = _axes(ax)
    xy = np.asarray(xy, float)
    ax.plot(xy[:, 0], xy[:, 1], "o", ms=4, color="C0", label="image points")
    if labels:
        for i, (x, y) in enumerate(xy):
            ax.annotate(str(i + 1), (x, y), xytext=(3, 3), textcoords="offset points", fontsize=10)
    if image is not None:
        c = np.array([image.x0, image.y0])
        ax.plot(*c, "+", ms=12, color="k", label="principal point")
        rmax = np.linalg.norm(xy - c, axis=1).max()
        t = np.linspace(0, 2 * np.pi, 181)
        for r in np.linspace(rmax / rings, rmax, rings):
            ax.plot(c[0] + r * np.cos(t), c[1] + r * np.sin(t), color="0.85", lw=0.8, zorder=0)
    if residuals is not None:
        v = np.asarray(residuals, float)
        ax.quiver(
            xy[:, 0], xy[:, 1], v[:, 0], v[:, 1], angles="xy", scale_units="xy",
            scale=1.0 / scale, color="C3", width=0.004, label=f"residuals × {scale:g}",
        )  # fmt: skip
    ax.set_aspect("equal")
    _image_axes_labels(ax, np.abs(xy).max())
    ax.legend(loc="best", fontsize=10)
    return fig


def _image_axes_labels(ax, extent: float) -> None:
    """Label the image axes in m, or in km (ticks thinned) when the image spans > 5 km."""
    if extent <= 5000.0:
        ax.set_xlabel("x_B [m]")
        ax.set_ylabel("y_B [m]")
        return
    from matplotlib.ticker import FuncFormatter, MaxNLocator

    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_locator(MaxNLocator(nbins=6))
        axis.set_major_formatter(FuncFormatter(lambda v, _pos: f"{v / 1000:g}"))
    ax.set_xlabel("x_B [km]")
    ax.set_ylabel("y_B [km]")


def _equal_3d(ax) -> None:
    """Equal scale on the three axes of a 3D plot (spheres look round)."""
    lims = np.array([ax.get_xlim3d(), ax.get_ylim3d(), ax.get_zlim3d()])
    ax.set_box_aspect(lims[:, 1] - lims[:, 0])


def plot_scene_3d(
    stations: list[dict], circles: list[dict] | None = None, points: ArrayLike | None = None,
    *, candidates: ArrayLike | None = None, ax=None,
):  # fmt: skip
    """3D view: stations with axes, projection circles, object points, candidates.

    Parameters
    ----------
    stations : list of dict
        From :func:`orientviz.radar.scene.station_scene`.
    circles : list of dict, optional
        From :func:`orientviz.radar.scene.circle_scene` (one per image).
    points : array_like, shape (n, 3), optional
        Object points.
    candidates : array_like, shape (2, 3), optional
        Trilateration candidates.
    ax : 3D Axes, optional
    """
    fig, ax = _axes(ax, projection="3d", figsize=(7.0, 6.0))
    for k, st in enumerate(stations):
        c = f"C{k}"
        ax.scatter(*st["station"], color=c, s=40, marker="^")
        ax.plot(*st["axis"].T, color=c, lw=2)
        ax.plot(*st["reference"].T, color=c, lw=1, ls="--")
        ax.text(*st["station"], f" {st['name']}", color=c, fontsize=10)
    for k, cs in enumerate(circles or []):
        for poly in cs["polylines"]:
            ax.plot(*poly.T, color=f"C{k}", lw=0.5, alpha=0.5)
    if points is not None:
        P = np.asarray(points, float)
        ax.scatter(P[:, 0], P[:, 1], P[:, 2], color="k", s=8)
    if candidates is not None:
        Cd = np.asarray(candidates, float)
        ax.scatter(Cd[:, 0], Cd[:, 1], Cd[:, 2], color="C3", s=60, marker="*")
        for q, name in zip(Cd, ("candidate 1", "candidate 2")):
            ax.text(*q, f" {name}", color="C3", fontsize=10)
    _equal_3d(ax)
    ax.set_xlabel("X [m]")
    ax.set_ylabel("Y [m]")
    ax.set_zlabel("Z [m]")
    return fig


def plot_trilateration(scene: dict, *, ax=None):
    """Three range spheres (as wireframes) and both trilateration candidates.

    ``scene`` from :func:`orientviz.radar.scene.trilateration_scene`.
    """
    fig, ax = _axes(ax, projection="3d", figsize=(7.0, 6.0))
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 25), np.linspace(0, np.pi, 13))
    for k, (c, r) in enumerate(zip(scene["centres"], scene["radii"])):
        ax.plot_wireframe(
            c[0] + r * np.cos(u) * np.sin(v), c[1] + r * np.sin(u) * np.sin(v),
            c[2] + r * np.cos(v), color=f"C{k}", lw=0.3, alpha=0.4,
        )  # fmt: skip
        ax.scatter(*c, color=f"C{k}", s=30)
    cand = scene["candidates"]
    ax.scatter(cand[:, 0], cand[:, 1], cand[:, 2], color="C3", s=80, marker="*")
    for q, name in zip(cand, ("lower", "upper")):
        ax.text(*q, f" {name}", color="C3")
    _equal_3d(ax)
    ax.set_xlabel("X [m]")
    ax.set_ylabel("Y [m]")
    ax.set_zlabel("Z [m]")
    ax.set_title(f"three spheres: two candidates (discriminant {scene['discriminant']:.3g} m²)")
    return fig


def plot_correlations(result, *, names: list[str] | None = None, ax=None):
    """Correlation matrix of an adjustment as a heat map (abs(ρ) near 1: weak geometry).

    ``names`` restricts the plot to some parameters (default: all of a small problem,
    or the ``"image2"`` block of a relative orientation).
    """
    fig, ax = _axes(ax, figsize=(5.5, 4.5))
    C = result.correlations()
    all_names = list(result.names)
    if names is None:
        names = all_names[result.groups["image2"]] if "image2" in result.groups else all_names
    idx = [all_names.index(n) for n in names]
    C = C[np.ix_(idx, idx)]
    im = ax.imshow(C, vmin=-1, vmax=1, cmap="RdBu_r")
    ax.set_xticks(range(len(names)), names, rotation=45, ha="right")
    ax.set_yticks(range(len(names)), names)
    for i in range(len(names)):
        for j in range(len(names)):
            ink = "white" if abs(C[i, j]) > 0.6 else "black"  # readable on the dark ends of the map
            ax.text(j, i, f"{C[i, j]:.2f}", ha="center", va="center", fontsize=10, color=ink)
    fig.colorbar(im, ax=ax, label="correlation ρ")
    return fig


def plot_fig8(
    paper: ArrayLike, orientviz: ArrayLike, *, spread: ArrayLike | None = None,
    columns: list[str] | None = None, title: str = "", unit: str = "", ax=None,
):  # fmt: skip
    """One row of Fig. 8: paper vs orientviz per column, with the rounding spread.

    Parameters
    ----------
    paper, orientviz : array_like, shape (10,)
        Values (NaN where none).
    spread : array_like, shape (10,), optional
        ±σ of orientviz's value over the rounding (error bars).
    columns : list of str, optional
        Column labels.
    """
    fig, ax = _axes(ax, figsize=(8.0, 3.5))
    x = np.arange(len(paper))
    ax.bar(x - 0.2, np.asarray(paper, float), 0.4, label="Geier 1973", color="0.6")
    ax.bar(
        x + 0.2, np.asarray(orientviz, float), 0.4, label="orientviz", color="C0",
        yerr=None if spread is None else np.asarray(spread, float), capsize=3,
    )  # fmt: skip
    ax.axhline(0, color="k", lw=0.6)
    ax.set_xticks(x, columns or [str(i + 1) for i in x], rotation=30, ha="right", fontsize=10)
    ax.set_ylabel(unit)
    ax.set_title(title)
    ax.legend(fontsize=10)
    fig.tight_layout()
    return fig
