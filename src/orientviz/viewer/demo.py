"""What the viewer shows: the :class:`Demo` record.

A demo (built in, :mod:`orientviz.viewer.demos`; a solved problem file,
:mod:`orientviz.viewer.solved`; a pair or radar scene) is a title, a description and
either a block state for the block scene and panel or an ``extra`` builder, or both.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from .state import BlockState


@dataclass
class Demo:
    """What the viewer shows.

    Attributes
    ----------
    name, title : str
    description : str
        Markdown shown at the top of the panel.
    state : BlockState or None
        A block for the scene and the orientation/adjustment panel.
    extra : callable or None
        ``extra(app) -> dict``: adds further nodes and controls to the
        :class:`~orientviz.viewer.app.ViewerApp` (``app.server``, ``app.scene`` — the
        block scene or None —, ``app.guard``, ``app.report``). The dict may hold
        ``"camera"`` = (position, look_at, size) for scenes without a block.
    message : str or None
        Shown in the panel at the start (e.g. why the adjustment did not converge).
    solution : Solution or None
        A problem file's solution (:mod:`orientviz.viewer.solved`), for the panel.
    background : BackgroundSolve or None
        The solve still to run (:mod:`orientviz.viewer.background`): the viewer shows
        ``state`` at the file's start values meanwhile and takes its solution at the end.
    """

    name: str
    title: str
    description: str
    state: BlockState | None = None
    extra: Callable[[Any], dict] | None = None
    message: str | None = None
    solution: Any = None
    background: Any = None
