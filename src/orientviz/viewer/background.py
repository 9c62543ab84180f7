"""A solve that runs while the viewer already shows the block: one thread, its progress, its end.

The viewer opens a large problem file whose start values are complete (an imported
reconstruction: COLMAP's or a BAL file's own estimate) at those values at once and runs
the solve here (:func:`orientviz.viewer.solved.solve_target` with ``background=True``);
the application takes the solution when the solve ends
(:meth:`orientviz.viewer.app.ViewerApp.take_background`). The solve itself is
``orientviz solve``'s, unchanged: this module only runs it in a thread, counts its
iterations and can stop it between two iterations.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

#: Seconds a background solve waits (at its next iteration) when a browser connects: the
#: page's first picture gets the CPU (software WebGL shares the two cores with the solve).
FIRST_PICTURE_HOLD: float = 3.0

#: Seconds ``orientviz view``'s background solve waits for a first browser before it
#: begins anyway (a browser connecting meanwhile gets :data:`FIRST_PICTURE_HOLD` first).
FIRST_BROWSER_WAIT: float = 5.0


class Cancelled(Exception):
    """Raised inside the solve's iteration callback to stop a background solve."""


class BackgroundSolve:
    """``solve(callback) -> Solved`` run once, in a daemon thread or at once.

    Parameters
    ----------
    solve : callable
        ``solve(callback)``: the solve; ``callback(iteration)`` is called with each new
        :class:`~orientviz.adjust.result.Iteration` (None: no progress wanted).
    shown : float
        σ̂0 (unitless) of the state shown while the solve runs (the file's start values).

    Attributes
    ----------
    iteration : Iteration or None
        The last iteration the solve reported.
    result : object or None
        What ``solve`` returned, once it has ended.
    error : BaseException or None
        What it raised instead.
    done : threading.Event
        Set when the solve has ended and ``on_done`` (of :meth:`start`) has returned.
    """

    def __init__(self, solve: Callable[[Any], Any], shown: float) -> None:
        self.solve = solve
        self.shown = float(shown)
        self.iteration: Any = None
        self.result: Any = None
        self.error: BaseException | None = None
        self.done = threading.Event()
        self._cancel = threading.Event()
        self._thread: threading.Thread | None = None
        self._hold_until = 0.0
        self._held = False

    def hold(self, seconds: float = FIRST_PICTURE_HOLD) -> None:
        """Let the solve wait at its next iteration (or before it begins, see
        :meth:`start`) until ``seconds`` from now."""
        self._hold_until = max(self._hold_until, time.monotonic() + seconds)
        self._held = True

    def _begin(self, wait: float) -> None:
        """Wait before the solve begins: until a hold (a browser's) has passed, or
        ``wait`` seconds if no hold comes."""
        deadline = time.monotonic() + wait
        while not self._cancel.is_set():
            now = time.monotonic()
            if now >= (self._hold_until if self._held else deadline):
                return
            self._cancel.wait(0.05)
        raise Cancelled("the viewer was stopped")

    def _progress(self, iteration: Any, on_iteration: Callable[[Any], None] | None) -> None:
        while not self._cancel.is_set() and time.monotonic() < self._hold_until:
            self._cancel.wait(0.05)  # held (:meth:`hold`)
        if self._cancel.is_set():
            raise Cancelled("the viewer was stopped")
        self.iteration = iteration
        if on_iteration is not None:
            on_iteration(self)

    def run(self) -> Any:
        """Solve now, in this thread, and return the result."""
        self.result = self.solve(lambda it: self._progress(it, None))
        self.done.set()
        return self.result

    def start(
        self,
        on_done: Callable[[BackgroundSolve], None],
        on_iteration: Callable[[BackgroundSolve], None] | None = None,
        wait: float = 0.0,
    ) -> None:
        """Solve in a daemon thread; ``on_done(self)`` when it ends (result or error set),
        ``on_iteration(self)`` after each iteration. ``wait`` (s): the thread begins the
        solve after a :meth:`hold` made meanwhile has passed, or after ``wait`` seconds
        without one (0: at once)."""

        def work() -> None:
            try:
                if wait > 0 or self._held:
                    self._begin(wait)
                self.result = self.solve(lambda it: self._progress(it, on_iteration))
            except Cancelled:
                return
            except Exception as exc:  # handed to on_done: the viewer shows it
                self.error = exc
            try:
                on_done(self)
            finally:
                self.done.set()

        self._thread = threading.Thread(target=work, name="orientviz-solve", daemon=True)
        self._thread.start()

    def cancel(self) -> None:
        """Stop the solve at its next iteration (its result is then never taken)."""
        self._cancel.set()

    def wait(self, timeout: float | None = None) -> bool:
        """Wait until the solve has ended and its result was taken; False on timeout."""
        return self.done.wait(timeout)

    @property
    def running(self) -> bool:
        """True while the solve has not ended."""
        return not self.done.is_set()

    def status(self) -> str:
        """One line for the panel: what runs and what is shown meanwhile."""
        it = self.iteration
        now = "starting" if it is None else f"iteration {int(it.index)}, σ0 {float(it.sigma0):.6g}"
        return (
            f"**solving in the background** as `orientviz solve` does ({now}); shown until it "
            f"ends: the file's own start values (σ̂0 {self.shown:.6g} there); actions wait for "
            "the solution"
        )
