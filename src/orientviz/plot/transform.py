"""Figures of a 3D similarity (absolute orientation) result: control layout and residuals.

Plan view of the control points in the object frame (m, X right, Y up); planimetric
residuals ``(v_X, v_Y)`` as arrows, height residuals ``v_Z`` as vertical bars beside
the point (up = positive), both enlarged by the same factor. Sign ``v = f(x̂) − l``:
an arrow points from the given control coordinate to the transformed model point.
"""

from __future__ import annotations

import numpy as np

from .style import subplots

#: Marker per kind of control point: full XYZ, planimetric XY, height Z.
MARKERS = {"XYZ": ("^", "#2874a6"), "XY": ("s", "#27ae60"), "Z": ("o", "#d35400")}


def control_kind(used: np.ndarray) -> list[str]:
    """'XYZ', 'XY', 'Z' or '' per row of an (n, 3) mask of used control coordinates."""
    out = []
    for u in np.asarray(used, bool):
        out.append("XYZ" if u.all() else "XY" if u[0] and u[1] else "Z" if u[2] else "")
    return out


def plot_transform_residuals(result, *, scale: float | None = None, ax=None, labels: bool = True):
    """Control layout and residuals of :func:`~orientviz.orientation.absolute.similarity_transform`.

    Parameters
    ----------
    result : Adjustment
        Result of ``similarity_transform`` (uses ``transformed``, ``used``,
        ``residuals_xyz``).
    scale : float, optional
        Exaggeration of the residuals; default so the largest spans ~12 % of the plot.
    ax : matplotlib.axes.Axes, optional
    labels : bool, default True
        Write the point ids (from the residual labels).

    Returns
    -------
    matplotlib.figure.Figure
    """

    P = np.asarray(result.transformed)
    used = np.asarray(result.used)
    v = np.asarray(result.residuals_xyz)
    if ax is None:
        _, ax = subplots(figsize=(6, 5.5))
    fig = ax.figure
    span = float(np.ptp(P[:, :2], axis=0).max()) or 1.0
    vmax = float(np.nanmax(np.abs(v))) if np.isfinite(v).any() else 0.0
    if scale is None:
        scale = 0.12 * span / vmax if vmax > 0 else 1.0
    kinds = control_kind(used)
    for kind, (marker, colour) in MARKERS.items():
        sel = np.array([k == kind for k in kinds])
        if sel.any():
            ax.plot(P[sel, 0], P[sel, 1], marker, color=colour, ms=7, label=f"control {kind}")
    other = np.array([k == "" for k in kinds])
    if other.any():
        ax.plot(P[other, 0], P[other, 1], ".", color="0.5", label="model point (no control)")
    vxy = np.nan_to_num(v[:, :2])
    has_xy = used[:, 0] | used[:, 1]
    ax.quiver(P[has_xy, 0], P[has_xy, 1], vxy[has_xy, 0] * scale, vxy[has_xy, 1] * scale,
              angles="xy", scale_units="xy", scale=1.0, color="k", width=0.004)  # fmt: skip
    hz = used[:, 2]
    off = 0.015 * span
    for x, y, dz in zip(P[hz, 0], P[hz, 1], v[hz, 2]):
        ax.plot(
            [x + off, x + off], [y, y + dz * scale], color="#d35400", lw=3, solid_capstyle="butt"
        )
    if labels and result.obs_labels:
        ids = []
        for lab in result.obs_labels[-int(used.sum()) :]:
            pid = lab.rsplit("/", 1)[0]
            if pid not in ids:
                ids.append(pid)
        rows = np.flatnonzero(used.any(axis=1))
        for r, pid in zip(rows, ids):
            ax.text(P[r, 0] - 2.5 * off, P[r, 1] + off, pid, fontsize=8, ha="right")
    ax.set_aspect("equal")
    ax.ticklabel_format(useOffset=False, style="plain")
    ax.margins(0.12)
    ax.set_xlabel("X [m]")
    ax.set_ylabel("Y [m]")
    ax.legend(loc="best", fontsize=8)
    ax.set_title(
        f"residuals × {scale:.3g} (largest {vmax * 100:.1f} cm); "
        f"bars: v_Z, arrows: v_XY; σ̂0 = {result.sigma0:.2f}",
        fontsize=9,
    )
    return fig
