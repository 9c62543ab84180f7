"""The viewer inside a notebook: a live IFrame plus a static picture of the same scene.

:func:`show_inline` starts the viser viewer on 127.0.0.1 with a free port, shows it in
the notebook as an IFrame and, above it, a matplotlib picture of the same scene
(:func:`scene_figure`: cameras, points, exaggerated residual vectors coloured by their
size), so that a saved notebook or the book still shows the block when no server runs.
Stop the server with ``app.stop()`` when done (the kernel's exit stops it too)::

    from orientviz.viewer.inline import show_inline
    app = show_inline((block, adjustment))
    ...
    app.stop()

The picture uses the viewer's own geometry (:class:`~orientviz.viewer.block_geometry.
BlockGeometry`), so it draws what the viewer draws: scene frame = object coordinates −
the frame origin, in m, Z up.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .app import ViewerApp, resolve_content
from .block_geometry import COLORS, BlockGeometry
from .geometry import frustum_segments


def scene_figure(
    content: Any,
    *,
    exaggeration: float | None = None,
    ax: Any = None,
    elev: float = 30.0,
    azim: float = -65.0,
    title: str | None = None,
) -> Any:
    """A static 3D picture (matplotlib) of what the viewer shows for ``content``.

    The axes read object coordinates (m, or a reconstruction's model units), not the
    viewer's scene frame centred on the block.

    Parameters
    ----------
    content : Block, (Block, Adjustment) or demo name
        As for :func:`~orientviz.viewer.app.open_viewer` (demos with a block).
    exaggeration : float, optional
        Factor for the residual vectors (default: the viewer's automatic choice, the
        median vector a third of a point spacing).
    ax : matplotlib 3D Axes, optional
        Draw into this axes (default: a new figure).
    elev, azim : float
        View direction in degrees.
    title : str, optional
        Axes title (default: what is shown and the exaggeration).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt
    from matplotlib.colors import to_hex
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    demo = resolve_content(content)
    if demo.state is None:
        raise ValueError(f"the demo {demo.name!r} has no block to draw")
    geo = BlockGeometry(demo.state)
    if ax is None:
        fig = plt.figure(figsize=(9, 6))
        ax = fig.add_subplot(projection="3d")
    fig = ax.figure
    rgb = {k: np.array(v) / 255.0 for k, v in COLORS.items()}
    # the viewer draws in a frame centred on the block; the picture reads object coordinates
    o = np.asarray(geo.frame.origin, float)
    ax.add_collection3d(
        Line3DCollection(
            g_segments(geo) + o, colors=to_hex(rgb["frustum"]), linewidths=0.8, label="cameras"
        )
    )
    for name, pts in geo.points_by_role().items():
        if len(pts):
            size = 3 if name == "tie" else 30
            marker = "." if name == "tie" else "^"
            ax.scatter(*(pts + o).T, s=size, c=[rgb[name]], marker=marker,
                       label=f"{name} points", depthshade=False)  # fmt: skip
    k = geo.auto_exaggeration() if exaggeration is None else float(exaggeration)
    seg, col = geo.residuals(k)
    seg = seg + o
    ax.add_collection3d(Line3DCollection(seg, colors=col[:, 0] / 255.0, linewidths=1.2))
    allp = np.vstack([seg.reshape(-1, 3), geo.frustum_corners().reshape(-1, 3) + o])
    lo, hi = np.nanmin(allp, axis=0), np.nanmax(allp, axis=0)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect((hi - lo) / max(hi[0] - lo[0], 1e-9))
    ax.view_init(elev=elev, azim=azim)
    unit = demo.state.units.length_name  # m, or a reconstruction's model units
    ax.set_xlabel(f"X [{unit}]")
    ax.set_ylabel(f"Y [{unit}]")
    ax.set_zlabel(f"Z [{unit}]")
    kind = demo.state.scores()[1]
    ax.set_title(title or f"{demo.title}: residual vectors ×{k:,.0f}, colour = {kind} (red ≥ 4)")
    ax.legend(loc="upper left", fontsize=10)
    return fig


def g_segments(geo: BlockGeometry) -> np.ndarray:
    """Frustum edges (m·8, 2, 3) of all images in the scene frame."""
    return frustum_segments(geo.frustum_corners())


def show_inline(
    content: Any,
    *,
    height: int = 500,
    picture: bool = True,
    exaggeration: float | None = None,
) -> ViewerApp:
    """Start the viewer on 127.0.0.1 (free port) and show it in the notebook.

    Parameters
    ----------
    content : Block, (Block, Adjustment), demo name or problem file
        What to show.
    height : int
        Height of the IFrame in pixels.
    picture : bool
        Also display :func:`scene_figure` (readable without a running server).
    exaggeration : float, optional
        Residual exaggeration of the picture.

    Returns
    -------
    ViewerApp
        The running viewer; call ``app.stop()`` when done.
    """
    import matplotlib.pyplot as plt
    from IPython.display import display

    app = ViewerApp(content, host="127.0.0.1", port=0, verbose=False)
    try:
        if picture:
            fig = scene_figure(app.demo if app.demo is not None else content,
                               exaggeration=exaggeration)  # fmt: skip
            display(fig)
            plt.close(fig)
        app.show(height=height)
    except BaseException:
        app.stop()
        raise
    return app
