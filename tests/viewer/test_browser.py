"""The viewer in a real headless Chromium: it renders, and a slider moved in the page
re-orients the image on the Python side and redraws the residuals."""

import time

import numpy as np
import pytest

import orientviz as ov
from orientviz.viewer.app import ViewerApp
from orientviz.viewer.demos import demo_from_block

from .browser import gui_control, number_box, wait_for

pytestmark = [pytest.mark.browser, pytest.mark.slow]  # about 10 s and 6 s with software WebGL

SHOT = "/tmp/orientviz_viewer_browser.png"


def test_viewer_renders_and_slider_updates_python(browser_page, block):
    from PIL import Image

    rng = np.random.default_rng(2)
    block.observations.xy += rng.normal(0, 0.005, block.observations.xy.shape)
    demo = demo_from_block(block)
    app = ViewerApp(demo, port=0, verbose=False)
    try:
        page = browser_page
        page.goto(app.url)
        page.wait_for_selector("[role=slider]", timeout=30_000)
        assert wait_for(lambda: len(app.server.get_clients()) > 0), "the page never connected"
        time.sleep(3.0)  # let the scene arrive and render
        page.screenshot(path=SHOT)
        img = np.asarray(Image.open(SHOT).convert("RGB"), dtype=float)
        scene = img[:, : int(img.shape[1] * 0.7)]  # left of the GUI panel
        background = np.median(scene.reshape(-1, 3), axis=0)
        drawn = np.mean(np.abs(scene - background).sum(axis=2) > 60)
        # not blank: frustums, points and residuals cover a visible part of the view
        assert scene.std() > 10
        assert drawn > 0.005, f"only {drawn:.4f} of the scene pixels differ from the background"

        st = app.demo.state
        before = np.asarray(app.scene.nodes["residuals"].points).copy()
        omega0 = st.block.images.angles[0, 0]
        client = next(iter(app.server.get_clients().values()))
        eye = np.array(client.camera.position)
        distance = np.linalg.norm(eye - np.array(client.camera.look_at))
        thumb = gui_control(page, "omega [gon]")
        thumb.focus()
        for _ in range(5):
            thumb.press("ArrowRight")  # 5 steps of 1 c
        ok = wait_for(lambda: abs(app.panel.handles["omega"].value - 0.05) < 1e-9, timeout=20)
        assert ok, f"slider value on the Python side: {app.panel.handles['omega'].value}"
        time.sleep(0.5)  # the page reports its camera every 50 ms
        moved = np.linalg.norm(np.array(client.camera.position) - eye)
        assert moved < 1e-6 * distance, f"the arrow keys on the slider moved the camera {moved:.3g}"
        assert wait_for(
            lambda: abs(st.block.images.angles[0, 0] - (omega0 + ov.to_rad(0.05, "gon"))) < 1e-12
        )
        after = np.asarray(app.scene.nodes["residuals"].points)
        changed = np.any(np.abs(after - before) > 0, axis=(1, 2))
        # exactly the rays of image 0 got new residual vectors
        np.testing.assert_array_equal(changed, st.block.observations.image == 0)
        page.screenshot(path=SHOT.replace(".png", "_after.png"))

        # a value typed into a dial's number box (ended with Enter) reaches Python
        box = number_box(page, "X0 [m]")
        box.fill("0.3")
        box.press("Enter")
        assert wait_for(lambda: app.panel.handles["X0"].value == 0.3, timeout=20)

        # a button pressed in the page runs one adjustment iteration on the Python side
        page.get_by_role("button", name="one iteration").click()
        assert wait_for(lambda: len(st.history) == 2, timeout=30), "no iteration after the click"
        assert wait_for(lambda: app.panel.handles["iteration"].max == 1)
        # the iteration set the dials back to 0; the next value pasted into the box (one
        # input event, no key pressed: a paste from the context menu) reaches Python too
        assert wait_for(lambda: number_box(page, "X0 [m]").input_value() == "0", timeout=20)
        number_box(page, "X0 [m]").fill("0.5")
        arrived = wait_for(lambda: app.panel.handles["X0"].value == 0.5, timeout=10)
        shown = number_box(page, "X0 [m]").input_value()
        assert arrived, (
            f"the pasted 0.5 was dropped (Python: {app.panel.handles['X0'].value}, box: {shown!r})"
        )
        with app.gate.lock:  # let the button's callback finish before the server stops
            pass
    finally:
        app.stop()


def test_exported_html_renders_without_a_server(browser_page, block, tmp_path):
    from PIL import Image

    from orientviz.viewer.app import export_html

    out = export_html(demo_from_block(block), tmp_path / "snapshot.html")
    page = browser_page
    page.goto(out.resolve().as_uri())
    page.wait_for_selector("canvas", timeout=30_000)
    time.sleep(4.0)
    shot = SHOT.replace(".png", "_export.png")
    page.screenshot(path=shot)
    img = np.asarray(Image.open(shot).convert("RGB"), dtype=float)
    background = np.median(img.reshape(-1, 3), axis=0)
    drawn = np.mean(np.abs(img - background).sum(axis=2) > 60)
    assert drawn > 0.005, f"only {drawn:.4f} of the pixels differ from the background"
