"""Figures of interior orientation: residual vectors at the fiducial marks."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .style import FONT, new_figure


def plot_fiducial_residuals(calibrated: ArrayLike, residuals: dict[str, ArrayLike], *,
                            exaggeration: float | None = None, title: str | None = None):  # fmt: skip
    """Residual vectors at the fiducial marks, one panel per transformation.

    Parameters
    ----------
    calibrated : array_like, shape (n, 2)
        Calibrated fiducial coordinates, mm.
    residuals : dict of str to array_like, shape (n, 2) or (2n,)
        Residuals (mm) per model name, e.g. ``{"similarity": …, "affine": …}``.
    exaggeration : float, optional
        Vector scale; default: the largest residual drawn 30 mm long.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    xy = np.asarray(calibrated, dtype=float)
    res = {k: np.asarray(v, dtype=float).reshape(-1, 2) for k, v in residuals.items()}
    big = max(float(np.max(np.linalg.norm(v, axis=1))) for v in res.values())
    ex = exaggeration or 30.0 / max(big, 1e-12)
    fig, axes = new_figure((3.4 * len(res), 3.9), ncols=len(res), squeeze=False)
    for ax, (name, v) in zip(axes[0], res.items()):
        ax.plot(xy[:, 0], xy[:, 1], "+", color="k", ms=10)
        ax.quiver(xy[:, 0], xy[:, 1], v[:, 0] * ex, v[:, 1] * ex, angles="xy", scale_units="xy",
                  scale=1.0, color="#c0392b", width=0.012)  # fmt: skip
        rms = float(np.sqrt(np.mean(v**2))) * 1000
        ax.set_title(f"{name}: RMS {rms:.1f} µm", fontsize=FONT["title"])
        ax.set_aspect("equal")
        lim = 1.35 * float(np.max(np.abs(xy)))
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim, lim)
        ax.set_xlabel("x [mm]", fontsize=FONT["label"])
        ax.tick_params(labelsize=FONT["tick"])
    axes[0, 0].set_ylabel("y [mm]", fontsize=FONT["label"])
    fig.suptitle(
        title or f"residuals at the fiducial marks (vectors ×{ex:.0f})", fontsize=FONT["suptitle"]
    )
    fig.tight_layout()
    return fig
