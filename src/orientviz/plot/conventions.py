"""Figures of orientviz's frames and signs: object frame, camera, image frame, ω φ κ.

The drawings are schematic (not to scale: the principal distance is drawn about a
quarter of the flying height) but every element is computed with the library's own
conventions — :func:`orientviz.rotation.matrix_from_opk` for R (image → object) and
:func:`orientviz.camera.project` for the image point — so the figure cannot disagree
with the code.
"""

from __future__ import annotations

import numpy as np

from ..camera import project
from ..rotation import matrix_from_opk
from .style import figure, subplots

#: Colours of the object axes X, Y, Z and of the image frame.
AXIS_COLOURS = ("#c0392b", "#27ae60", "#2874a6")
IMAGE_COLOUR = "#7d3c98"


def _arc(ax3d, centre, axis: int, radius: float, colour: str, label: str, label_at) -> None:
    """A counter-clockwise arc (seen from the positive axis) with an arrow head.

    ``label_at`` is the label's offset from ``centre`` (object units), chosen per axis
    so that the label sits clear of the axis arrow and its letter.
    """
    t = np.linspace(0.15 * np.pi, 1.75 * np.pi, 60)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    pts = np.zeros((t.size, 3))
    pts[:, i] = radius * np.cos(t)
    pts[:, j] = radius * np.sin(t)
    pts += centre
    ax3d.plot(pts[:, 0], pts[:, 1], pts[:, 2], color=colour, lw=1.5)
    tip, before = pts[-1], pts[-6]
    ax3d.quiver(*before, *(tip - before), color=colour, arrow_length_ratio=1.0, lw=1.5)
    ax3d.text(*(centre + np.asarray(label_at)), label, color=colour, fontsize=13,
              ha="center", va="center")  # fmt: skip


def plot_frames(
    omega: float = 0.12,
    phi: float = -0.10,
    kappa: float = 0.35,
    *,
    sequence: str = "opk",
    ax=None,
):
    """3D schematic: object frame, projection centre, tilted image plane, c, ω φ κ, one ray.

    Parameters
    ----------
    omega, phi, kappa : float
        Attitude of the drawn camera in radians (sequence ``sequence``).
    sequence : {"opk", "pok"}, default "opk"
        Rotation sequence used to build R (image → object).
    ax : mpl_toolkits.mplot3d.Axes3D, optional
        Axes to draw into (a new figure if None).

    Returns
    -------
    matplotlib.figure.Figure
    """

    if ax is None:
        fig = figure(figsize=(7, 6))
        ax = fig.add_subplot(projection="3d")
    fig = ax.figure
    R = matrix_from_opk(omega, phi, kappa, sequence)
    X0 = np.array([1.5, 1.6, 4.6])
    c, half = 1.3, 1.0
    # object frame, with ω φ κ as right-handed turns about X, Y, Z
    for k, name in enumerate("XYZ"):
        e = np.zeros(3)
        e[k] = 3.0
        ax.quiver(0, 0, 0, *e, color=AXIS_COLOURS[k], arrow_length_ratio=0.08, lw=2)
        ax.text(*(e * 1.07), name, color=AXIS_COLOURS[k], fontsize=13, fontweight="bold")
        label_at = ((0.42, 0.0, 0.42), (0.0, 0.0, 0.62), (-0.55, 0.3, 0.2))[k]
        _arc(ax, e * 0.6, k, 0.3, AXIS_COLOURS[k], ("ω", "φ", "κ")[k], label_at)
    ax.text2D(
        0.02,
        0.01,
        "object frame X, Y, Z (m), Z up; schematic, not to scale",
        transform=ax.transAxes,
        fontsize=9,
    )
    # image plane at z = −c in the image frame (positive position, between O and ground)
    corners = np.array([[half, half], [-half, half], [-half, -half], [half, -half], [half, half]])
    plane = X0 + np.column_stack([corners, np.full(5, -c)]) @ R.T
    ax.plot(plane[:, 0], plane[:, 1], plane[:, 2], color=IMAGE_COLOUR, lw=1.5)
    H = X0 + R @ np.array([0.0, 0.0, -c])
    for k, name in enumerate("xy"):
        e = np.zeros(3)
        e[k] = 0.8
        d = R @ e
        ax.quiver(*H, *d, color=IMAGE_COLOUR, arrow_length_ratio=0.15, lw=1.5)
        ax.text(*(H + d * 1.15), name, color=IMAGE_COLOUR, fontsize=12, fontweight="bold")
    ax.plot(*np.column_stack([X0, H]), color="k", lw=1.2)
    ax.text(*((X0 + H) / 2 + R @ np.array([-0.2, 0.0, 0.0])), "c", fontsize=12)
    ax.scatter(*X0, color="k", s=25)
    ax.text(*(X0 + np.array([0.1, 0.0, 0.15])), "O = (X0, Y0, Z0)", fontsize=10)
    ax.scatter(*H, color=IMAGE_COLOUR, s=12)
    ax.text(*(H + R @ np.array([-0.55, -0.3, 0.0])), "H'", color=IMAGE_COLOUR, fontsize=10)
    # one object point, its ray and its image point
    P = np.array([3.0, 0.5, 0.3])
    xy = project(P[None], X0, R, c)[0]
    p = X0 + R @ np.array([xy[0], xy[1], -c])
    ax.plot(*np.column_stack([X0, P]), ls="--", color="0.35", lw=1)
    ax.scatter(*P, color="k", s=25)
    ax.text(*(P + np.array([0.0, 0.12, 0.25])), "P = (X, Y, Z)", fontsize=10)
    ax.scatter(*p, color=IMAGE_COLOUR, s=18)
    ax.text(*(p + np.array([0.15, 0.0, -0.45])), "P' = (x, y)", color=IMAGE_COLOUR, fontsize=10)
    ax.set_xlim(0, 3.3)
    ax.set_ylim(0, 3.3)
    ax.set_zlim(-0.4, 5.0)  # room below the X axis for the footnote
    ax.set_box_aspect((3.3, 3.3, 5.4))
    ax.view_init(elev=16, azim=-62)
    ax.set_axis_off()
    seq_txt = "R = R_ω R_φ R_κ" if sequence == "opk" else "R = R_φ R_ω R_κ"
    ax.set_title(f"X − X0 = λ·R·(x − x0, y − y0, −c)ᵀ,  {seq_txt}", fontsize=10)
    return fig


def plot_image_frame(xy=(42.0, -27.0), *, x0: float = 0.0, y0: float = 0.0, ax=None):
    """The image (fiducial) frame seen from the projection centre, in mm.

    Parameters
    ----------
    xy : tuple of float
        An image point to mark, mm.
    x0, y0 : float
        Principal point in mm.
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = subplots(figsize=(4.5, 4.5))
    fig = ax.figure
    h = 115.0
    ax.add_patch(plt.Rectangle((-h, -h), 2 * h, 2 * h, fill=False, color="0.3"))
    for sx, sy in ((1, 0), (-1, 0), (0, 1), (0, -1)):  # fiducial marks
        ax.plot(sx * (h - 4), sy * (h - 4), marker="+", color="0.3", ms=10)
    ax.annotate(
        "",
        (h * 0.8, 0),
        (-h * 0.8, 0),
        arrowprops=dict(arrowstyle="->", color=IMAGE_COLOUR, lw=1.5),
    )
    ax.annotate(
        "",
        (0, h * 0.8),
        (0, -h * 0.8),
        arrowprops=dict(arrowstyle="->", color=IMAGE_COLOUR, lw=1.5),
    )
    ax.text(h * 0.55, 5, "x (flight)", color=IMAGE_COLOUR, fontsize=10)
    ax.text(4, h * 0.84, "y", color=IMAGE_COLOUR, fontsize=10)
    ax.text(-h * 0.95, -h * 0.87, "z ⊙ towards the viewer (the projection centre)", fontsize=8)
    ax.plot(x0, y0, marker="x", color="k")
    ax.text(x0 + 3, y0 - 10, "H' (x0, y0)", fontsize=9)
    ax.plot(*xy, marker="o", color="k", ms=4)
    ax.text(xy[0] + 3, xy[1] + 4, f"P' ({xy[0]:g}, {xy[1]:g}) mm", fontsize=9)
    ax.set_xlim(-h - 8, h + 8)
    ax.set_ylim(-h - 8, h + 8)
    ax.set_aspect("equal")
    ax.set_xticks([-100, 0, 100])
    ax.set_yticks([-100, 0, 100])
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_title("image frame (positive, seen from above)", fontsize=10)
    return fig


def plot_conventions(omega: float = 0.12, phi: float = -0.10, kappa: float = 0.35, *, fig=None):
    """The conventions figure of the book: :func:`plot_frames` beside :func:`plot_image_frame`.

    Parameters
    ----------
    omega, phi, kappa : float
        Attitude of the drawn camera, rad, sequence ω-φ-κ.
    fig : matplotlib.figure.Figure, optional
        Figure to draw into (a new 6.2 × 10 in figure if None: the 3D schematic above the
        image frame, so that both stay readable at the book's column width).

    Returns
    -------
    matplotlib.figure.Figure
    """

    if fig is None:
        fig = figure(figsize=(6.2, 10.0))
    grid = fig.add_gridspec(2, 1, height_ratios=(1.25, 1.0))
    ax3 = fig.add_subplot(grid[0], projection="3d")
    ax2 = fig.add_subplot(grid[1])
    plot_frames(omega, phi, kappa, ax=ax3)
    plot_image_frame(ax=ax2)
    fig.tight_layout()
    return fig
