"""One gate for the viewer's GUI callbacks: one at a time, errors reported, none after stop.

viser runs each GUI callback on a thread of its own. Every callback of a viewer (the
block panel's, a demo's, the design studio's) is wrapped by the same
:class:`CallbackGate`, so a click while a redraw is still running waits for it, an
exception becomes a message for the user instead of ending the server, and a callback
that arrives after the viewer stopped does nothing (nothing is sent to a stopped server).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any


class CallbackGate:
    """Serialise, report and finally shut off GUI callbacks.

    Parameters
    ----------
    report : callable
        ``report(message)``: shows an exception's message to the user.
    """

    def __init__(self, report: Callable[[str], None]) -> None:
        self.report = report
        #: set by :meth:`close`: every later call of a wrapped callback does nothing
        self.closed = False
        #: held while a callback runs; other threads that change the scene (the solve in
        #: the background delivering its result) take it too
        self.lock = threading.RLock()

    def wrap(
        self, fn: Callable[..., Any], skip: Callable[[], bool] | None = None
    ) -> Callable[..., None]:
        """``fn`` as a GUI callback; ``skip()`` true ignores a call (e.g. the panel's own
        setting of its sliders echoing back)."""

        def wrapped(*args: Any) -> None:
            if skip is not None and skip():
                return
            with self.lock:
                if self.closed:
                    return
                try:
                    fn(*args)
                except Exception as exc:  # shown to the user, the server keeps running
                    self.report(f"{type(exc).__name__}: {exc}")

        return wrapped

    def close(self) -> None:
        """Wait for a callback still running, then ignore every later one."""
        with self.lock:
            self.closed = True
