"""Helpers of the real-browser tests: polling, GUI controls, screenshots of the scene."""

from __future__ import annotations

import io
import time
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np

#: share of the window width left of the GUI panel (1280 px window: panel from ~940 px)
SCENE_WIDTH = 0.72
#: colour distance (RGB, 0-255) within which a pixel counts as an element's colour (the
#: renderer's colour management shifts flat colours by up to ~30)
TOLERANCE = 45.0


def wait_for(predicate, timeout=30.0, step=0.1):
    """Poll ``predicate`` until it is true or ``timeout`` seconds have passed."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(step)
    return False


def gui_control(page, label, selector="[role=slider]"):
    """The control (``selector``) of the GUI row labelled ``label`` (e.g. a slider's thumb)."""
    row = page.locator("div", has=page.locator("label", has_text=label)).filter(
        has=page.locator(selector)
    )
    return row.last.locator(selector).first


def number_box(page, label):
    """The number box beside the slider labelled ``label``."""
    return gui_control(page, label, "input:not([type=hidden])")


@contextmanager
def served(content) -> Iterator:
    """A viewer on ``content`` at 127.0.0.1 (a free port), stopped afterwards."""
    from orientviz.viewer.app import ViewerApp

    app = ViewerApp(content, port=0, verbose=False)
    try:
        yield app
    finally:
        app.stop()


def scene_image(page) -> np.ndarray:
    """The scene part (left of the panel) of a screenshot, float RGB (h, w, 3)."""
    from PIL import Image

    img = np.asarray(Image.open(io.BytesIO(page.screenshot())).convert("RGB"), dtype=float)
    return img[:, : int(img.shape[1] * SCENE_WIDTH)]


def drawn_share(img: np.ndarray) -> float:
    """Share of pixels that differ clearly from the (median) background."""
    background = np.median(img.reshape(-1, 3), axis=0)
    return float(np.mean(np.abs(img - background).sum(axis=2) > 60))


def colour_count(img: np.ndarray, rgb) -> int:
    """Number of pixels within :data:`TOLERANCE` of colour ``rgb``."""
    return int((np.linalg.norm(img - np.asarray(rgb, float), axis=2) < TOLERANCE).sum())


def changed_share(a: np.ndarray, b: np.ndarray) -> float:
    """Share of pixels whose colour changed by more than 40 in some channel."""
    return float(np.mean(np.abs(a - b).max(axis=2) > 40))


def open_demo(page, app, min_drawn: float = 0.01) -> np.ndarray:
    """Load the viewer page, wait until the scene is drawn; return its screenshot."""
    page.goto(app.url)
    page.wait_for_selector("canvas", timeout=60_000)
    assert wait_for(lambda: len(app.server.get_clients()) > 0, 60), "the page never connected"
    # the "software WebGL" notice is about this headless machine, not the viewer
    page.add_style_tag(content=".mantine-Notifications-root {display: none !important}")
    shot = {}

    def drawn():
        shot["img"] = scene_image(page)
        return drawn_share(shot["img"]) > min_drawn

    assert wait_for(drawn, 60, 0.5), f"the scene stayed blank ({drawn_share(shot['img']):.4f})"
    time.sleep(1.0)  # let the last nodes of the scene arrive
    img = scene_image(page)
    assert img.std() > 10, "the scene has no contrast"
    return img


def wait_for_picture(page, before: np.ndarray | None, test, timeout: float = 30.0) -> np.ndarray:
    """Poll screenshots until ``test(after)`` holds; return the last one.

    ``before`` (a screenshot, or None) only serves the message when the deadline passes.
    """
    shot = {}

    def ok():
        shot["img"] = scene_image(page)
        return test(shot["img"])

    if not wait_for(ok, timeout, 0.5):
        changed = "" if before is None else f" ({changed_share(before, shot['img']):.4f} changed)"
        raise AssertionError(f"the picture never became what the test expects{changed}")
    return shot["img"]
