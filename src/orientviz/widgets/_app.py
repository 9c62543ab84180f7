"""The layout and redraw loop shared by the lesson apps: controls and a text panel on the
left, a figure on the right, everything recomputed when a control changes.

The apps supply three plain functions, so that what they compute stays testable without
a browser: ``compute(*control values) -> state``, ``describe(state) -> str`` and
``draw(state) -> Figure``. A state that cannot be computed because the geometry does not
determine it (:class:`~orientviz.errors.NotDeterminableError`) is reported in the text
panel and the last figure is kept.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from ..errors import NotDeterminableError


def control_app(
    controls: Sequence[Any],
    compute: Callable[..., Any],
    describe: Callable[[Any], str],
    draw: Callable[[Any], Any],
) -> Any:
    """Wire ``controls`` to ``compute`` and show its result as text and a figure.

    Parameters
    ----------
    controls : sequence of ipywidgets value widgets
        Their values are passed to ``compute`` in this order, on every change.
    compute : callable
        ``compute(*values) -> state``; may raise ``NotDeterminableError``.
    describe : callable
        ``describe(state) -> str``, printed in the text panel under the controls.
    draw : callable
        ``draw(state) -> matplotlib.figure.Figure``, shown beside the controls and closed.

    Returns
    -------
    ipywidgets.HBox
        ``HBox([VBox([*controls, text]), figure output])``; ``.redraw()`` recomputes.
    """
    import ipywidgets as W
    import matplotlib.pyplot as plt
    from IPython.display import display

    out, text = W.Output(), W.Output()

    def redraw(*_: Any) -> None:
        with text:
            text.clear_output(wait=True)
            try:
                state = compute(*(c.value for c in controls))
            except NotDeterminableError as exc:
                print(f"not determinable: {exc}")
                return
            print(describe(state))
        with out:
            out.clear_output(wait=True)
            fig = draw(state)
            display(fig)
            plt.close(fig)

    for c in controls:
        c.observe(redraw, names="value")
    redraw()
    box = W.HBox([W.VBox([*controls, text]), out])
    box.redraw = redraw
    return box
