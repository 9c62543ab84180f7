"""Figures of the sparse normal equations: block patterns, the reduced system, fill-in."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..bundle.sparsity import bandwidth, cholesky_fill
from .style import FONT, new_figure


def plot_normal_pattern(pattern: ArrayLike, n_images: int, *, ax=None, title: str | None = None):
    """The non-zero blocks of a bundle's normal matrix (images first, then points).

    Parameters
    ----------
    pattern : array_like of bool, shape (m + q, m + q)
        Block pattern (:func:`orientviz.bundle.sparsity.block_pattern`), drawn with each
        image block 6 and each point block 3 unknowns wide.
    n_images : int
        m, the number of image blocks (the rest are points).
    ax : matplotlib Axes, optional
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    P = np.asarray(pattern, dtype=bool)
    size = np.where(np.arange(len(P)) < n_images, 6, 3)
    edges = np.concatenate([[0], np.cumsum(size)])
    if ax is None:
        fig, ax = new_figure((4.6, 4.6))
    else:
        fig = ax.figure
    from matplotlib.collections import PolyCollection

    i, k = np.nonzero(P)
    boxes = [[(edges[c], edges[r]), (edges[c + 1], edges[r]), (edges[c + 1], edges[r + 1]),
              (edges[c], edges[r + 1])] for r, c in zip(i, k)]  # fmt: skip
    colour = np.where((i < n_images) & (k < n_images), "#1f4e79",
                      np.where((i >= n_images) & (k >= n_images), "#27ae60", "#c0392b"))  # fmt: skip
    ax.add_collection(PolyCollection(boxes, facecolors=colour, edgecolors="none"))
    u = int(edges[-1])
    e = int(edges[n_images])
    ax.axhline(e, color="0.3", lw=0.8)
    ax.axvline(e, color="0.3", lw=0.8)
    ax.set_xlim(0, u)
    ax.set_ylim(u, 0)
    ax.set_aspect("equal")
    ax.tick_params(labelsize=FONT["tick"])
    ax.set_xlabel(f"unknown (first {e}: images, then points)", fontsize=FONT["label"])
    fill = 100.0 * float(np.sum(np.where(P, size[:, None] * size[None, :], 0))) / u**2
    ax.set_title(title or f"N: {u} unknowns, {fill:.1f} % non-zero\nU blue, V green, W red",
                 fontsize=FONT["title"])  # fmt: skip
    fig.tight_layout()
    return fig


def plot_reduced_patterns(patterns: dict[str, tuple[ArrayLike, ArrayLike | None]]):
    """The reduced system S (6×6 blocks) under several numberings, with Cholesky fill-in.

    Parameters
    ----------
    patterns : dict of str to (pattern, order)
        Per panel title: the image-level pattern of S and an order (new → old index;
        None = as numbered).

    Returns
    -------
    matplotlib.figure.Figure
        Black: non-zero blocks of S (lower half); red: fill-in of its Cholesky factor.
    """
    fig, axes = new_figure((3.4 * len(patterns), 3.9), ncols=len(patterns), squeeze=False)
    for ax, (name, (pattern, order)) in zip(axes[0], patterns.items()):
        P = np.asarray(pattern, dtype=bool)
        if order is not None:
            o = np.asarray(order, dtype=int)
            P = P[np.ix_(o, o)]
        L = cholesky_fill(P)
        low = np.tril(P)
        img = np.ones(P.shape + (3,))
        img[L & ~low] = (0.85, 0.2, 0.15)
        img[low] = (0.0, 0.0, 0.0)
        ax.imshow(img, interpolation="nearest")
        ax.set_title(f"{name}\nband {bandwidth(P)}, fill-in {int(np.sum(L & ~low))} blocks",
                     fontsize=FONT["title"])  # fmt: skip
        ax.tick_params(labelsize=FONT["tick"])
        ax.set_xlabel("image", fontsize=FONT["label"])
    fig.tight_layout()
    return fig
