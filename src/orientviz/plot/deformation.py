"""Figures of image and model deformation (Ackermann's Bild 6), from the data of
:mod:`orientviz.simulate`.

Image fields: x along the flight direction, mm; vectors exaggerated so that µm become
visible. Model fields: object frame in m (X along the base), planimetric vectors
exaggerated, heights as coloured contours in cm. :func:`plot_deformation_frame` draws one
frame of the animation between a field without and with self-calibration.
"""

from __future__ import annotations

import textwrap

import numpy as np

from ..errors import InputError
from ..simulate import ImageField, animate
from .style import subplots


def _axes(ax, **kw):

    if ax is None:
        fig, ax = subplots(**kw)
        return fig, ax
    return ax.figure, ax


def plot_image_field(
    field,
    *,
    ax=None,
    exaggeration: float | None = None,
    title=None,
    xlabel: str = "x [mm] (flight direction)",
):
    """Quiver plot of an :class:`~orientviz.simulate.ImageField`.

    Parameters
    ----------
    field : ImageField
        Grid positions (mm) and error vectors (mm).
    ax : matplotlib Axes, optional
        Axes to draw into; a new figure if None.
    exaggeration : float, optional
        Vector exaggeration; default: the largest vector drawn as 1/8 of the grid width.
    title : str, optional
        Title (default: the field's name and largest error in µm).
    xlabel : str, optional
        Label of the x axis (a terrestrial camera has no flight direction).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = _axes(ax, figsize=(5, 5))
    width = float(np.ptp(field.xy[:, 0])) or 1.0
    big = max(float(np.max(np.hypot(field.d[:, 0], field.d[:, 1]), initial=0.0)), 1e-12)
    ex = exaggeration if exaggeration is not None else width / 8.0 / big
    ax.quiver(
        field.xy[:, 0], field.xy[:, 1], ex * field.d[:, 0], ex * field.d[:, 1],
        angles="xy", scale_units="xy", scale=1.0, color="#c0392b", width=0.004,
    )  # fmt: skip
    ax.plot(field.xy[:, 0], field.xy[:, 1], ".", color="0.5", ms=3)
    (xa, ya), (xb, yb) = field.xy.min(axis=0), field.xy.max(axis=0)  # the format: the grid's extent
    ax.plot([xa, xb, xb, xa, xa], [ya, ya, yb, yb, ya], color="0.3", lw=0.8)
    tips = np.vstack([field.xy, field.xy + ex * field.d])  # keep every arrow inside
    pad = 0.03 * width
    ax.set_xlim(min(tips[:, 0].min(), xa) - pad, max(tips[:, 0].max(), xb) + pad)
    ax.set_ylim(min(tips[:, 1].min(), ya) - pad, max(tips[:, 1].max(), yb) + pad)
    ax.set_aspect("equal")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("y [mm]")
    name = textwrap.shorten(field.name, 60)
    ax.set_title(title or f"{name}\nmax {field.max_um:.1f} µm, vectors ×{ex:.0f}", fontsize=10)
    return fig


def plot_model_field(
    field, *, component: str = "planimetry", ax=None, exaggeration=None, title=None
):
    """One component of a :class:`~orientviz.simulate.ModelField`.

    Parameters
    ----------
    field : ModelField
        Ground grid (m) and deformation (m).
    component : {"planimetry", "height"}
        Planimetric vectors (ΔX, ΔY) or height deformation ΔZ as filled contours (cm).
    ax : matplotlib Axes, optional
        Axes to draw into; a new figure if None.
    exaggeration : float, optional
        Planimetric vector exaggeration (default: largest vector = 1/8 of the model width).
    title : str, optional
        Title (default: the field's name, component and RMS).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = _axes(ax, figsize=(5, 5))
    X, Y = field.xyz[:, 0], field.xyz[:, 1]
    rms = field.rms() * 100.0
    if component == "planimetry":
        width = float(np.ptp(X)) or 1.0
        big = max(float(np.max(np.hypot(field.d[:, 0], field.d[:, 1]), initial=0.0)), 1e-12)
        ex = exaggeration if exaggeration is not None else width / 8.0 / big
        ax.quiver(
            X, Y, ex * field.d[:, 0], ex * field.d[:, 1],
            angles="xy", scale_units="xy", scale=1.0, color="#2874a6", width=0.008,
        )  # fmt: skip
        ax.plot(X, Y, ".", color="0.5", ms=3)
        sub = f"plan: RMS X {rms[0]:.1f} / Y {rms[1]:.1f} cm, ×{ex:.0f}"
    elif component == "height":
        r, c = field.shape
        dz = field.d[:, 2].reshape(r, c) * 100.0
        lim = max(float(np.max(np.abs(dz))), 1e-9)
        cs = ax.contourf(
            X.reshape(r, c), Y.reshape(r, c), dz, levels=np.linspace(-lim, lim, 17), cmap="RdBu_r"
        )
        fig.colorbar(cs, ax=ax, label="ΔZ [cm]", shrink=0.8)
        ax.plot(X, Y, ".", color="0.3", ms=2)
        sub = f"height, RMS Z {rms[2]:.1f} cm"
    else:
        raise InputError(f"component: expected 'planimetry' or 'height', got {component!r}")
    ax.set_aspect("equal")
    ax.set_xlabel("X [m] (along the base)")
    ax.set_ylabel("Y [m]")
    ax.set_title(title or f"{textwrap.shorten(field.name, 60)}\n{sub}", fontsize=10)
    return fig


def plot_deformation_comparison(without, with_, *, axes=None, exaggeration=None):
    """2 × 2 figure: planimetry and height of a model, without and with self-calibration.

    Parameters
    ----------
    without, with_ : ModelField
        The same model oriented from raw and from self-calibrated image coordinates.
    axes : array of 4 matplotlib Axes, optional
        Axes to draw into (row-major: plan without, plan with, height without, height
        with); a new figure if None.
    exaggeration : float, optional
        Common planimetric exaggeration (default: from the field *without*).

    Returns
    -------
    matplotlib.figure.Figure
    """

    if axes is None:
        fig, axes = subplots(2, 2, figsize=(9, 8.2))
    axes = np.asarray(axes).ravel()
    if exaggeration is None:
        width = float(np.ptp(without.xyz[:, 0])) or 1.0
        big = max(float(np.max(np.hypot(without.d[:, 0], without.d[:, 1]))), 1e-12)
        exaggeration = width / 8.0 / big
    for k, (f, label) in enumerate(((without, "without"), (with_, "with self-calibration"))):
        plot_model_field(f, component="planimetry", ax=axes[k], exaggeration=exaggeration)
        plot_model_field(f, component="height", ax=axes[2 + k])
        axes[k].set_title(f"{label}: " + axes[k].get_title().split("\n")[-1], fontsize=10)
        axes[2 + k].set_title(f"{label}: " + axes[2 + k].get_title().split("\n")[-1], fontsize=10)
    fig = axes[0].figure
    fig.suptitle(f"model deformation — {textwrap.shorten(without.name, 80)}", fontsize=10)
    fig.tight_layout()
    return fig


def plot_deformation_frame(
    without,
    with_,
    t: float,
    *,
    exaggeration: float | None = None,
    ax=None,
    title: str | None = None,
):
    """One frame of the animation between two deformation fields of the same grid.

    The frame is :func:`orientviz.simulate.animate` at ``t``: every grid point
    moved by ``exaggeration · ((1 − t) · d_without + t · d_with)``. Arrows go from the
    grid point to its exaggerated position (one arrow per grid point); the moved points
    are coloured by the deformation at ``t`` in true size — ΔZ in cm for a model field,
    the vector length in µm for an image field — on a colour scale fixed by both fields,
    so that frames of different t compare directly.

    Parameters
    ----------
    without, with_ : ModelField or ImageField
        The fields without (t = 0) and with (t = 1) self-calibration, on the same grid
        (:func:`orientviz.simulate.model_field`, ``image_field``). Model
        fields: ground points and deformation in m; image fields: mm.
    t : float
        Position between the two states, 0 ≤ t ≤ 1.
    exaggeration : float, optional
        Factor on the deformation (dimensionless). Default: the largest planimetric
        vector of ``without`` drawn at 1/8 of the grid width (the same for every t).
    ax : matplotlib Axes, optional
        Axes to draw into; a new figure if None.
    title : str, optional
        Title (default: t and the exaggeration).

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    InputError
        If the fields lie on different grids or t is outside [0, 1] (from ``animate``).
    """
    image = isinstance(without, ImageField)
    base = without.xy if image else without.xyz
    if exaggeration is None:
        width = float(np.ptp(base[:, 0])) or 1.0
        big = max(float(np.max(np.hypot(without.d[:, 0], without.d[:, 1]), initial=0.0)), 1e-12)
        exaggeration = width / 8.0 / big
    moved = animate(without, with_, float(t), float(exaggeration))
    d = (1.0 - float(t)) * without.d + float(t) * with_.d  # true size at t
    if image:
        value = np.hypot(d[:, 0], d[:, 1]) * 1e3
        top = max(
            float(np.max(np.hypot(f.d[:, 0], f.d[:, 1]), initial=0.0)) for f in (without, with_)
        )
        clim, cmap, label, unit = (0.0, max(top * 1e3, 1e-9)), "viridis", "abs(Δxy) [µm]", "mm"
    else:
        value = d[:, 2] * 100.0
        top = max(float(np.max(np.abs(f.d[:, 2]), initial=0.0)) for f in (without, with_))
        lim = max(top * 100.0, 1e-9)
        clim, cmap, label, unit = (-lim, lim), "RdBu_r", "ΔZ [cm]", "m"
    fig, ax = _axes(ax, figsize=(5.5, 4.5))
    ax.quiver(
        base[:, 0], base[:, 1], moved[:, 0] - base[:, 0], moved[:, 1] - base[:, 1],
        angles="xy", scale_units="xy", scale=1.0, color="0.35", width=0.004,
    )  # fmt: skip
    pts = ax.scatter(
        moved[:, 0], moved[:, 1], c=value, cmap=cmap, vmin=clim[0], vmax=clim[1], s=28,
        edgecolors="0.2", linewidths=0.4, zorder=3,
    )  # fmt: skip
    fig.colorbar(pts, ax=ax, label=label, shrink=0.85)
    ax.set_aspect("equal")
    if image:
        ax.set_xlabel(f"x [{unit}] (flight direction)")
        ax.set_ylabel(f"y [{unit}]")
    else:
        ax.set_xlabel(f"X [{unit}] (along the base)")
        ax.set_ylabel(f"Y [{unit}]")
    ax.set_title(
        title or f"t = {float(t):.2f} (0 without, 1 with self-calibration), ×{exaggeration:.0f}",
        fontsize=10,
    )
    return fig


def plot_field_split(split, *, axes=None, exaggeration: float | None = None):
    """Three quiver panels of a :class:`~orientviz.simulate.FieldSplit`.

    The image error field, the part the parameter set (with the orientation
    deformations) describes and the remainder, all with one exaggeration so that the
    arrows compare directly.

    Parameters
    ----------
    split : FieldSplit
        From :func:`orientviz.simulate.split_field` (grid in mm, vectors in mm).
    axes : sequence of 3 matplotlib Axes, optional
        Axes to draw into; a new 1 × 3 figure if None.
    exaggeration : float, optional
        Vector exaggeration (dimensionless); default: the largest vector of the whole
        field drawn at 1/8 of the grid width.

    Returns
    -------
    matplotlib.figure.Figure
    """

    if axes is None:
        _, axes = subplots(1, 3, figsize=(9.6, 3.9))
    axes = np.asarray(axes).ravel()
    g = split.grid
    if exaggeration is None:
        width = float(np.ptp(g.xy[:, 0])) or 1.0
        big = max(float(np.max(np.hypot(g.d[:, 0], g.d[:, 1]), initial=0.0)), 1e-12)
        exaggeration = width / 8.0 / big
    part = np.asarray(split.described(g.xy, np.zeros(g.xy.shape[0], np.int64)), float)
    sx, sy, _ = np.asarray(split.share) * 100.0
    panels = (  # two short lines each: three panels share the 6.2 in of a book column
        (g.d, "field", split.rms_um[0]),
        (part, f"described (x {sx:.0f} %, y {sy:.0f} %)", split.rms_um[1]),
        (g.d - part, "remainder", split.rms_um[2]),
    )
    for ax, (d, label, rms) in zip(axes, panels):
        plot_image_field(
            ImageField(g.xy, d, g.shape, g.name), ax=ax, exaggeration=exaggeration,
            title=f"{label}\nRMS {rms:.2f} µm, ×{exaggeration:.0f}",
        )  # fmt: skip
    lo = np.min([[ax.get_xlim()[0], ax.get_ylim()[0]] for ax in axes[:3]], axis=0)
    hi = np.max([[ax.get_xlim()[1], ax.get_ylim()[1]] for ax in axes[:3]], axis=0)
    for ax in axes[:3]:  # one frame for all panels
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
    fig = axes[0].figure
    fig.suptitle(textwrap.shorten(split.name, 90), fontsize=10)
    fig.tight_layout()
    return fig
