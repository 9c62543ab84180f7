"""Sliders that the server moves as well as the user (dials reset after an adjustment,
scrubbers, the selected image).

viser 1.1.1 draws a slider with a number box beside it (Mantine's ``NumberInput``, built
on react-number-format 5.4.5). That box remembers the caret range of the last key pressed
in it (Enter after typing "0.3", say) until the next input event. When the server then
sets the slider to a value written with fewer characters ("0"), the next value that
arrives in one input event without a key press (pasted from the context menu, dropped,
filled in by the browser) is read against that stale range, which lies past the end of
the new text; the box treats such an edit as one inside its suffix and keeps the old
text. The value is lost without a message. A fresh component has no such memory, so a
:class:`Sliders` group re-creates a slider (same place, label, range, step, hint and
state; a new viser handle) when it sets the value of a slider that a browser has
changed since it was made. Sliders that no browser touched are set as usual.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

Callback = Callable[[Any], None]


class Sliders:
    """A group of viser sliders whose values the server also sets.

    Parameters
    ----------
    gui : viser.GuiApi
        The server's (or a client's) GUI API.
    handles : dict
        The panel's dictionary of handles; ``handles[key]`` always holds the slider's
        current viser handle (it changes when the slider is re-created).
    """

    def __init__(self, gui: Any, handles: dict[str, Any]) -> None:
        self.gui = gui
        self.handles = handles
        self._folder: dict[str, Any] = {}
        self._callbacks: dict[str, list[Callback]] = {}
        self._touched: dict[str, bool] = {}
        self._lock = threading.RLock()
        #: how many sliders were re-created (read by tests and benchmarks)
        self.recreated = 0

    def add(
        self,
        key: str,
        folder: Any,
        label: str,
        low: float,
        high: float,
        step: float,
        initial: float,
        **options: Any,
    ) -> Any:
        """Add a slider inside ``with folder:`` (the viser folder handle the caller is in;
        a re-created slider goes there too) and keep it as ``handles[key]``.

        ``low``, ``high``, ``step`` and ``initial`` are in the slider's own unit; ``options``
        are viser's (``hint``, ``disabled``, ``visible``, ``order``). Returns the viser handle.
        """
        handle = self.gui.add_slider(label, low, high, step, initial, **options)
        self._folder[key] = folder
        self._callbacks[key] = []
        self._touched[key] = False
        self._watch(key, handle)
        self.handles[key] = handle
        return handle

    def on_update(self, key: str, fn: Callback) -> None:
        """Call ``fn(event)`` whenever slider ``key`` changes (in a browser or by :meth:`set`)."""
        with self._lock:
            self._callbacks[key].append(fn)
            self.handles[key].on_update(fn)

    def touched(self, key: str) -> bool:
        """Whether a browser has changed slider ``key`` since it was (re-)created."""
        return self._touched[key]

    def set(self, key: str, value: float) -> None:
        """Set slider ``key`` to ``value`` from the server; its callbacks run as for viser's
        own assignment. A slider a browser has changed since it was made is re-created
        at ``value`` in its place (see the module's docstring), then its callbacks run."""
        with self._lock:
            old = self.handles[key]
            value = type(old.value)(value)
            if old.value == value:
                return
            if not self._touched[key]:
                old.value = value
                return
            new = self._recreate(key, old, value)
        from viser import GuiEvent  # GUI library only where a viewer runs

        for fn in list(self._callbacks[key]):
            fn(GuiEvent(client=None, client_id=None, target=new))

    # ------------------------------------------------------------------ internals
    def _watch(self, key: str, handle: Any) -> None:
        def mark(event: Any) -> None:
            if event.client_id is not None:  # a browser, not the server's own assignment
                self._touched[key] = True

        handle.on_update(mark)

    def _recreate(self, key: str, old: Any, value: float) -> Any:
        options = {
            "disabled": old.disabled,
            "visible": old.visible,
            "hint": old.hint,
            "order": old.order,
        }
        old.remove()
        with self._folder[key]:
            new = self.gui.add_slider(old.label, old.min, old.max, old.step, value, **options)
        self._touched[key] = False
        self._watch(key, new)
        for fn in self._callbacks[key]:
            new.on_update(fn)
        self.handles[key] = new
        self.recreated += 1
        return new
