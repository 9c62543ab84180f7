"""Arrow keys on a focused slider move the slider only, not the camera as well.

viser 1.1.1's page moves the camera while an arrow key (or W A S D Q E) is held, from
a ``keydown`` listener on the document (client/src/CameraControls.tsx, ``onKeyDown``).
It ignores keys typed into form fields (``isFormElement``: INPUT, TEXTAREA, SELECT,
contenteditable), but a slider's thumb is a ``div`` with ``role="slider"``, so an arrow
key that steps a focused slider also orbits the view. viser has no option for the
keyboard camera (neither ``configure_theme`` nor the scene API), and the camera-lock
leases that stop it are taken only by gestures inside the page.

The page renders ``gui.add_html`` content as HTML without sanitising it, so the server
can add one listener of its own there: on ``document.body``, below the page's root
(where React hands the key to the slider) and above the document (where the camera
listener waits), it stops an arrow key's ``keydown`` whose target lies inside a slider.
Arrow keys elsewhere (the canvas, nothing focused) still move the camera.
"""

from __future__ import annotations

from typing import Any

#: the listener, added once per page (a reconnect renders the element again)
SCRIPT = (
    "if(!window.orientvizSliderKeys){window.orientvizSliderKeys=true;"
    "document.body.addEventListener('keydown',function(e){"
    "var t=e.target;"
    "if(e.key.indexOf('Arrow')===0&&t&&t.closest&&t.closest('[role=slider]')){"
    "e.stopPropagation();}});}"
)

#: GUI order far behind every other element (the image element draws nothing)
LAST = 1e9


def keep_arrow_keys_on_sliders(server: Any) -> Any:
    """Add to ``server``'s page the listener that keeps arrow keys on a focused slider.

    The listener comes as the ``onerror`` handler of an image without content (it fails
    to load at once, hidden); returns viser's handle of that HTML element.
    """
    html = f'<img src="data:," alt="" style="display:none" onerror="{SCRIPT}">'
    return server.gui.add_html(html, order=LAST)
