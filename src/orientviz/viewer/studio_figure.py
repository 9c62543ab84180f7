"""A static picture of the design studio (matplotlib): the plan view of a design.

:func:`design_figure` draws what the studio's scene shows, seen from above: the points
coloured by the chosen quality measure with the studio's colour scale and a colour bar,
the control points as black diamonds, the projection centres and the flight lines, the
suggested control point. A lesson or the book shows it where no viewer runs; its axes
are labelled with the rows and columns of the point ids (``gRR_CCC``), so that a point
can be named from the picture.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .quality import STOPS
from .studio import (
    CONTROL_COLOUR,
    MEASURES,
    STATION_COLOUR,
    STRIP_COLOUR,
    SUGGESTED_COLOUR,
    Studio,
    point_values,
    scale_of,
)


def _grid_ticks(ids: list[str], values: np.ndarray, part: int) -> tuple[list, list]:
    """Tick positions (median coordinate) and labels of the id's row (0) or column (1)."""
    groups: dict[int, list[float]] = {}
    for name, v in zip(ids, values):
        if len(name) == 7 and name[0] == "g" and name[3] == "_":
            k = int(name[1:3]) if part == 0 else int(name[4:])
            groups.setdefault(k, []).append(float(v))
    keys = sorted(groups)
    return [float(np.median(groups[k])) for k in keys], [str(k) for k in keys]


def design_figure(
    studio: Studio, *, measure: str | None = None, ax: Any = None, title: str | None = None
) -> Any:
    """The plan view of the studio's current design, coloured by a quality measure.

    Parameters
    ----------
    studio : Studio
    measure : str, optional
        A key of :data:`~orientviz.viewer.studio.MEASURES` (default: the studio's).
    ax : matplotlib Axes, optional
        Draw into this axes (default: a new figure from :mod:`orientviz.plot.style`).
    title : str, optional
        Default: the method, the number of control points and the worst σ_Z.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import LinearSegmentedColormap, Normalize

    from ..plot.style import subplots  # matplotlib: only when a picture is drawn

    key = measure or studio.measure
    label, unit, _, worse_high = MEASURES[key]

    q = studio.quality
    b = studio.block
    vals = point_values(q, b, key)
    scale = scale_of(vals, key)
    if ax is None:
        fig, ax = subplots(figsize=(6.2, 4.4))
    fig = ax.figure
    P, X0 = b.points.xyz / 1e3, b.images.X0 / 1e3  # km
    for s in np.unique(b.images.strip):
        k = np.flatnonzero(b.images.strip == s)
        ax.plot(*X0[k, :2].T, "-", color=np.array(STRIP_COLOUR) / 255, lw=0.8, zorder=1)
    ax.plot(*X0[:, :2].T, "s", ms=3, color=np.array(STATION_COLOUR) / 255, zorder=2,
            label="projection centres")  # fmt: skip
    cols = scale.colours(vals) / 255.0
    ax.scatter(*P[:, :2].T, c=cols, s=28, zorder=3, edgecolors="none")
    c = q.control
    ax.scatter(*P[c, :2].T, marker="D", s=46, facecolors="none", zorder=4,
               edgecolors=np.array(CONTROL_COLOUR) / 255, linewidths=1.4,
               label="control")  # fmt: skip
    sug = studio.suggestion
    if sug is not None:
        ax.scatter(*P[[sug.point], :2].T, marker="*", s=160, zorder=5,
                   color=np.array(SUGGESTED_COLOUR) / 255, label="suggested control")  # fmt: skip
    stops = STOPS if worse_high else STOPS[::-1]
    cmap = LinearSegmentedColormap.from_list("studio", stops / 255.0)
    sm = ScalarMappable(norm=Normalize(scale.lo, scale.hi), cmap=cmap)
    bar = fig.colorbar(sm, ax=ax, shrink=0.85, pad=0.02)
    bar.set_label(f"{label}" + (f" [{unit}]" if unit else ""))
    ax.set_aspect("equal")
    xt, xl = _grid_ticks(b.points.ids, P[:, 0], 1)
    yt, yl = _grid_ticks(b.points.ids, P[:, 1], 0)
    if xt:
        ax.set_xticks(xt, xl)
        ax.set_yticks(yt, yl)
        ax.set_xlabel("column CCC of the point id gRR_CCC (X →)")
        ax.set_ylabel("row RR (Y →)")
    else:
        ax.set_xlabel("X [km]")
        ax.set_ylabel("Y [km]")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.18), ncol=3, frameon=False)
    if title is None:
        tie = ~c
        title = (
            f"{studio.method}: {int(c.sum())} control points, largest σ_Z "
            f"{np.nanmax(q.point_sigma[tie, 2]):.2f} m"
        )
    ax.set_title(title)
    return fig
