"""The viewer live inside a lesson: the student's own state in a viser scene in the notebook.

:func:`show_live` starts the viewer on 127.0.0.1 (a free port), shows it in the
notebook's output as an IFrame of the live server and returns the running
:class:`~orientviz.viewer.app.ViewerApp`; the lesson's code keeps the app and changes the
scene while the student works (``app.demo.state``, ``app.extra``). The output carries
the name of a static picture of the same scene in its metadata (key
:data:`SNAPSHOT_KEY`): the offline book shows ``book/_static/lesson_viewer/<name>.png`` in
its place (written by ``tools/make_lesson_snapshots.py``, which photographs the scene
the lesson itself built). Without a browser (a notebook executed by nbclient in the
tests) the server starts, nobody connects, and it stops with the kernel: a second or so.

The builders make the scenes of the lessons from what the student computed:

* :func:`iterations_demo` — a block at the states of the student's own iterations (the
  panel's iteration scrubber replays them);
* :func:`pair_passes_demo` — a stereo pair on the analog plotter, its five dials set to
  the student's passes (the scrubber under *Passes* replays them; :func:`set_pair_dials`
  turns the dials from the notebook);
* :func:`deformation_demo` — an adjusted block with the deformation view against the
  truth (and the comparison without / with self-calibration).
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..adjust import Adjustment
from ..block import Block
from ..orientation.plotter import AnalogPlotter
from .app import ViewerApp
from .deformation import deformation_extra
from .demos import Demo
from .history import Snapshot
from .pair_scene import PairView
from .state import BlockState

#: output metadata key holding the name of the book's static picture of the scene
SNAPSHOT_KEY = "orientviz_viewer_snapshot"


def start(content: Any) -> ViewerApp:
    """A viewer on 127.0.0.1 with a free port, without viser's start-up banner.

    Parameters
    ----------
    content : Demo, Block, (Block, Adjustment), demo name or problem file
        What to show (as for :class:`~orientviz.viewer.app.ViewerApp`).

    Returns
    -------
    ViewerApp
    """
    import rich  # viser prints its banner through rich's console (in Jupyter: as a display)

    console = rich.get_console()
    was_quiet, console.quiet = console.quiet, True
    quiet = io.StringIO()
    try:
        with contextlib.redirect_stdout(quiet), contextlib.redirect_stderr(quiet):
            return ViewerApp(content, host="127.0.0.1", port=0, verbose=False)
    finally:
        console.quiet = was_quiet


def iframe_html(url: str, height: int) -> str:
    """The HTML of the live view: an IFrame of the viewer at ``url``, ``height`` px high."""
    return (
        f'<iframe src="{url}" width="100%" height="{int(height)}" '
        'style="border:1px solid #ccc" title="orientviz viewer (live while the kernel runs)">'
        "</iframe>"
    )


def show_live(content: Any, snapshot: str, *, height: int = 520) -> ViewerApp:
    """Start the viewer for ``content`` and show it live in the notebook.

    Parameters
    ----------
    content : Demo, Block, (Block, Adjustment), demo name or problem file
        What to show.
    snapshot : str
        Name of the book's static picture of this scene (``book/_static/lesson_viewer/
        <snapshot>.png``), stored in the output's metadata under :data:`SNAPSHOT_KEY`.
    height : int
        Height of the IFrame in pixels.

    Returns
    -------
    ViewerApp
        The running viewer (``app.url``, ``app.demo``, ``app.extra``); ``app.stop()``
        stops it (the kernel's exit does too).
    """
    from IPython.display import display

    app = start(content)
    try:
        if app.messages:
            print("viewer:", app.messages[-1])
        text = f"orientviz viewer, live at {app.url} while this kernel runs"
        display(
            {"text/html": iframe_html(app.url, height), "text/plain": text},
            raw=True,
            metadata={SNAPSHOT_KEY: snapshot},
        )
    except BaseException:
        app.stop()
        raise
    return app


# ---------------------------------------------------------------------- lesson scenes
def iterations_demo(
    block: Block,
    states: Sequence[tuple[Any, Any, Any, float]],
    title: str = "Your iterations",
    description: str = "",
) -> Demo:
    """A block shown at the states of the student's own iterations.

    Parameters
    ----------
    block : Block
        Observations, roles and start values.
    states : sequence of (X0, angles, xyz, sigma0)
        State after 0, 1, 2, … iterations: projection centres (m, 3) m, angles (m, 3) rad
        in the block's sequence, points (p, 3) m, and the σ̂0 reported for it (NaN if none).
    title, description : str
        Panel heading and text.

    Returns
    -------
    Demo
        Its state's history holds the iterations (the panel's iteration scrubber replays
        them), and the state is at the last one.
    """
    if not states:
        raise ValueError("no iterations to show")
    state = BlockState(block)
    state.history = [
        Snapshot(
            "start" if k == 0 else f"iteration {k}",
            np.array(X0, dtype=float).reshape(block.n_images, 3),
            np.array(angles, dtype=float).reshape(block.n_images, 3),
            np.array(xyz, dtype=float).reshape(block.n_points, 3),
            float(s0),
        )
        for k, (X0, angles, xyz, s0) in enumerate(states)
    ]
    state.replay(len(state.history) - 1)
    return Demo("block", title, description or block.summary(), state)


def pair_passes_demo(
    pair: Any,
    passes: Sequence[Any],
    title: str = "Your passes",
    description: str = "",
) -> Demo:
    """A stereo pair on the analog plotter, its dials at the student's passes.

    Parameters
    ----------
    pair : orientviz.orientation.plotter.TruePair
        The photographs (``true_pair``; its ``config.sequence`` is the dials' axes).
    passes : sequence of array_like, shape (5,)
        The elements by, bz (machine mm), ω, φ, κ (rad) after 0, 1, 2, … passes.
    title, description : str
        Panel heading and text.

    Returns
    -------
    Demo
        The pair view (``app.extra["pair"]`` once started): dials at the last pass, the
        scrubber under *Passes* replays every pass; the dials stay free to turn.
    """

    settings = [np.asarray(p, dtype=float).reshape(5).copy() for p in passes]
    if not settings:
        raise ValueError("no passes to show")
    plotter = AnalogPlotter(pair, settings=settings[0])

    def build(app: Any) -> dict:
        view = PairView(app, plotter)
        out = view.build()
        view.snapshots = [s.copy() for s in settings]
        view._set(settings[-1])
        return out

    desc = description or (
        "Your passes on the pair: the scrubber under *Passes* steps through them; turn a "
        "dial and watch the y-parallax arrows."
    )
    return Demo("pair", title, desc, None, build)


def deformation_demo(
    block: Block,
    result: Adjustment,
    truth: Block,
    title: str = "Model deformation",
    description: str = "",
) -> Demo:
    """An adjusted block with the deformation view against the true points.

    Parameters
    ----------
    block : Block
        The block that was adjusted (start values).
    result : Adjustment
        Its adjustment (exterior orientations and points).
    truth : Block
        The same block with the true coordinates (a simulation's ``truth``).
    title, description : str
        Panel heading and text.

    Returns
    -------
    Demo
        The block panel plus the folder *Deformation* (adjusted − true points, morph,
        and the comparison without / with self-calibration).
    """

    state = BlockState(block, result)
    return Demo("block", title, description or block.summary(), state,
                deformation_extra(state, truth))  # fmt: skip


def mark_points(
    app: ViewerApp,
    name: str,
    xyz: Any,
    color: tuple[int, int, int] = (0, 170, 0),
    size: float | None = None,
) -> Any:
    """Add (or replace) a point cloud ``name`` at object coordinates ``xyz`` (n, 3) m.

    The points go through the scene frame of what ``app`` shows (the block scene's, or that
    of the pair or radar view in ``app.extra``); ``size`` defaults to 3 % of the scene.
    Returns the viser handle (set ``.points`` again through the same frame to move them).
    """
    frame = None
    if app.scene is not None:
        frame = app.scene.geo.frame
    for key in ("radar", "pair"):
        if frame is None and key in app.extra:
            frame = app.extra[key].frame
    if frame is None:
        raise ValueError("the viewer shows no scene with a frame")
    pts = frame.to_scene(np.atleast_2d(np.asarray(xyz, dtype=float))).astype(np.float32)
    return app.server.scene.add_point_cloud(
        name, pts, color, point_size=size or 0.03 * frame.size, point_shape="sparkle",
        precision="float32",
    )  # fmt: skip


def set_pair_dials(app: ViewerApp, settings: Any, refit: bool = False) -> None:
    """Turn the five dials of a pair view (:func:`pair_passes_demo`) to ``settings``.

    Parameters
    ----------
    app : ViewerApp
        A viewer showing a pair (``app.extra["pair"]``).
    settings : array_like, shape (5,)
        by, bz (machine mm), ω, φ, κ (rad).
    refit : bool
        Also choose the parallax arrows' scale anew for this state (it stays fixed otherwise,
        so that arrows of different states compare).
    """
    view = app.extra["pair"]
    view._set(np.asarray(settings, dtype=float).reshape(5))
    if refit:
        view.rescale()
