"""Figures of epipolar geometry: a point in the left image, its line in the right."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..orientation.epipolar import epipolar_distances, epipolar_lines
from .style import FONT, new_figure

_COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf", "#8c564b", "#e377c2")


def plot_epipolar_lines(xy_left: ArrayLike, xy_right: ArrayLike, E: ArrayLike, c: float, *,
                        half: float = 115.0, title: str | None = None):  # fmt: skip
    """Left image points and their epipolar lines in the right image.

    Parameters
    ----------
    xy_left, xy_right : array_like, shape (n, 2)
        Corresponding image points, mm (a few: each gets a colour).
    E : array_like, shape (3, 3)
        Essential matrix (d1ᵀ E d2 = 0, rays (x, y, −c)).
    c : float
        Principal distance, mm.
    half : float
        Half the image format, mm (the frame drawn and the lines' extent).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    p1 = np.asarray(xy_left, dtype=float)
    p2 = np.asarray(xy_right, dtype=float)
    lines = epipolar_lines(E, p1, c)
    dist = epipolar_distances(E, p1, p2, c)
    fig, (a1, a2) = new_figure((7.0, 3.9), ncols=2)
    t = np.linspace(-1.5 * half, 1.5 * half, 2)
    for k in range(len(p1)):
        col = _COLOURS[k % len(_COLOURS)]
        a1.plot(*p1[k], "o", color=col, ms=6)
        a1.annotate(str(k + 1), p1[k], xytext=(4, 4), textcoords="offset points",
                    fontsize=FONT["note"], color=col)  # fmt: skip
        a, b, d = lines[k]
        if abs(b) > abs(a):  # y as a function of x
            a2.plot(t, -(a * t + d) / b, "-", color=col, lw=1.2)
        else:
            a2.plot(-(b * t + d) / a, t, "-", color=col, lw=1.2)
        a2.plot(*p2[k], "o", color=col, ms=6)
        a2.annotate(str(k + 1), p2[k], xytext=(4, 4), textcoords="offset points",
                    fontsize=FONT["note"], color=col)  # fmt: skip
    for ax, name in ((a1, "left image: points"), (a2, "right image: epipolar lines")):
        ax.plot(
            [-half, half, half, -half, -half],
            [-half, -half, half, half, -half],
            color="0.4",
            lw=0.8,
        )
        ax.set_xlim(-1.1 * half, 1.1 * half)
        ax.set_ylim(-1.1 * half, 1.1 * half)
        ax.set_aspect("equal")
        ax.set_title(name, fontsize=FONT["title"])
        ax.set_xlabel("x [mm]", fontsize=FONT["label"])
        ax.tick_params(labelsize=FONT["tick"])
    a1.set_ylabel("y [mm]", fontsize=FONT["label"])
    rms = float(np.sqrt(np.mean(dist**2))) * 1000
    fig.suptitle(title or f"distance of the matches from their lines: RMS {rms:.1f} µm",
                 fontsize=FONT["suptitle"])  # fmt: skip
    fig.tight_layout()
    return fig
