"""Figures of the datum: one network, its error ellipses in several datums."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..adjust.ellipse import ellipse_outline, error_ellipse
from .style import FONT, new_figure


def plot_datum_ellipses(xy: ArrayLike, pairs: ArrayLike, cofactors: dict[str, ArrayLike], *,
                        datum_points: dict[str, ArrayLike] | None = None, sigma0: float = 1.0,
                        scale: float | None = None, unit: str = "m"):  # fmt: skip
    """A planar network with its standard error ellipses, one panel per datum.

    Parameters
    ----------
    xy : array_like, shape (p, 2)
        Point coordinates, ``unit``.
    pairs : array_like of int, shape (k, 2)
        Observed connections (drawn as thin lines).
    cofactors : dict of str to array_like, shape (2p, 2p)
        Cofactor (or covariance) matrix of the coordinates per datum name.
    datum_points : dict of str to array_like of int, optional
        Points that define each datum (marked with squares).
    sigma0 : float
        Scale of the cofactors (covariance = σ0² Q).
    scale : float, optional
        Ellipse exaggeration; default: the largest semi-axis over all panels drawn as 20 %
        of the network's extent.

    Returns
    -------
    matplotlib.figure.Figure
    """
    p = np.asarray(xy, dtype=float)
    pr = np.asarray(pairs, dtype=int)
    covs = {k: sigma0**2 * np.asarray(Q, dtype=float) for k, Q in cofactors.items()}
    blocks = {k: np.array([C[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] for i in range(len(p))])
              for k, C in covs.items()}  # fmt: skip
    amax = max(float(np.max(error_ellipse(B).a)) for B in blocks.values())
    extent = float(np.max(np.ptp(p, axis=0)))
    ex = scale or 0.2 * extent / max(amax, 1e-300)
    fig, axes = new_figure((3.5 * len(covs), 3.9), ncols=len(covs), squeeze=False)
    for ax, (name, B) in zip(axes[0], blocks.items()):
        for i, j in pr:
            ax.plot(p[[i, j], 0], p[[i, j], 1], "-", color="0.8", lw=0.8)
        for i in range(len(p)):
            ring = ellipse_outline(p[i], B[i] * ex**2)
            ax.plot(ring[:, 0], ring[:, 1], color="#1f4e79", lw=1.6)
            ax.annotate(
                str(i + 1), p[i], xytext=(-10, 5), textcoords="offset points", fontsize=FONT["note"]
            )
        ax.plot(p[:, 0], p[:, 1], "o", color="k", ms=3)
        if datum_points and name in datum_points:
            d = np.asarray(datum_points[name], dtype=int)
            ax.plot(p[d, 0], p[d, 1], "s", mfc="none", mec="#c0392b", ms=11, mew=2)
        a = error_ellipse(B).a
        ax.set_title(
            f"{name}\nlargest a = {1000 * float(np.max(a)):.1f} m{unit}", fontsize=FONT["title"]
        )
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(f"standard error ellipses ×{ex:.0f}", fontsize=FONT["suptitle"])
    fig.tight_layout()
    return fig
