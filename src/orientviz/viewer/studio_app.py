"""The design studio started from Python (a notebook): :func:`open_studio`."""

from __future__ import annotations

from .app import ViewerApp
from .demos import design_demo
from .studio import Studio


def open_studio(
    studio: Studio | None = None, *, port: int = 0, inline: bool = True, height: int = 650
) -> ViewerApp:
    """Start the studio on 127.0.0.1 (``port`` 0: a free one) on ``studio``, shared with the
    caller: what the panel changes, ``studio`` holds (call
    ``app.extra["studio"].redraw()`` after changing ``studio`` in code).

    Parameters
    ----------
    studio : Studio, optional
        Default: the studio's first design.
    port : int
    inline : bool
        Show the live studio in the notebook (an IFrame of the local server).
    height : int
        Its height in pixels.

    Returns
    -------
    ViewerApp
        Stop it with ``app.stop()``; the view is ``app.extra["studio"]``.
    """
    app = ViewerApp(design_demo(studio), host="127.0.0.1", port=port, verbose=not inline)
    if inline:
        app.show(height=height)
    return app
