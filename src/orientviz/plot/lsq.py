"""Figures of small least-squares problems: predicted precision against repetitions."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..adjust.ellipse import confidence_scale, ellipse_outline, error_ellipse, inside_fraction
from .style import FONT, new_figure


def plot_ellipse_check(samples: ArrayLike, estimate: ArrayLike, cov: ArrayLike, *, ax=None,
                       unit: str = "m", names: tuple[str, str] = ("X", "Y"),
                       p: float = 0.95, title: str | None = None):  # fmt: skip
    """Repeated estimates of a 2-D quantity against its predicted error ellipses.

    Parameters
    ----------
    samples : array_like, shape (k, 2)
        Estimates from k repetitions with fresh noise (a simulation), in ``unit``.
    estimate : array_like, shape (2,)
        Centre of the ellipses (the true value or one estimate), in ``unit``.
    cov : array_like, shape (2, 2)
        Predicted covariance (σ0² Q), in ``unit`` squared.
    ax : matplotlib Axes, optional
    unit : str
        Unit of the coordinates, for the labels.
    names : (str, str)
        Names of the two coordinates.
    p : float
        Probability of the second (confidence) ellipse.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    s = np.asarray(samples, dtype=float)
    c = np.asarray(estimate, dtype=float)
    C = np.asarray(cov, dtype=float)
    if ax is None:
        fig, ax = new_figure((6.0, 5.0))
    else:
        fig = ax.figure
    k = confidence_scale(p)
    f1, fp = inside_fraction(s, c, C, 1.0), inside_fraction(s, c, C, k)
    ax.plot(s[:, 0], s[:, 1], ".", ms=3, color="0.55", label=f"{len(s)} repetitions")
    e1 = ellipse_outline(c, C, 1.0)
    ep = ellipse_outline(c, C, k)
    ax.plot(
        e1[:, 0],
        e1[:, 1],
        color="#1f4e79",
        lw=2,
        label=f"standard ellipse: {100 * f1:.1f} % inside",
    )
    ax.plot(ep[:, 0], ep[:, 1], color="#c0392b", lw=2,
            label=f"{100 * p:.0f} % ellipse (×{k:.2f}): {100 * fp:.1f} % inside")  # fmt: skip
    ax.plot(*c[:2], "+", color="k", ms=12, mew=2)
    e = error_ellipse(C)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"{names[0]} [{unit}]", fontsize=FONT["label"])
    ax.set_ylabel(f"{names[1]} [{unit}]", fontsize=FONT["label"])
    ax.tick_params(labelsize=FONT["tick"])
    ax.legend(fontsize=FONT["legend"], loc="upper left", framealpha=0.9)
    ax.set_title(
        title
        or f"a = {float(e.a):.3g} {unit}, b = {float(e.b):.3g} {unit}, "
        f"θ = {np.degrees(float(e.theta)):.1f}°",
        fontsize=FONT["title"],
    )
    ax.ticklabel_format(useOffset=False)
    fig.tight_layout()
    return fig
