"""The live viewer inside a lesson, for real: lesson 05 run in JupyterLab in headless
Chromium, and the viser scene seen in the notebook's output.

JupyterLab is started as in ``test_jupyterlab.py`` (its helpers: a temporary root with a
copy of the lesson, its own Jupyter directories, ``--LabApp.expose_app_in_browser`` so the
test can run "Run All Cells" as a command). The lesson's last section calls
``orientviz.viewer.live.show_live``: a viser server in the lesson's kernel on 127.0.0.1
and an IFrame of it in the output. The test finds that IFrame in the output area, waits
for the viewer's WebGL canvas inside it and its panel ("Your passes", the five dials), and
checks that the canvas shows a scene: many non-background pixels of several colours.
"""

from __future__ import annotations

import io
import time

import numpy as np
import pytest
import test_jupyterlab as lab

from conftest import free_port

LESSON = "05_relative_orientation.ipynb"
OVERALL_S = 300.0  # generous: a cold start on a busy 2-core machine, 05 runs ~10-30 s


@pytest.mark.browser
@pytest.mark.slow
def test_lesson_shows_the_live_viewer_in_jupyterlab(browser_page, tmp_path):
    pytest.importorskip("jupyterlab", reason="JupyterLab is not installed (pip install .[all])")
    pytest.importorskip("ipykernel", reason="ipykernel is not installed")
    pytest.importorskip("viser", reason="viser is not installed (pip install .[viewer])")
    from PIL import Image

    deadline = time.monotonic() + OVERALL_S
    root = tmp_path / "root"
    root.mkdir()
    (root / LESSON).write_bytes((lab.ROOT / "notebooks" / LESSON).read_bytes())
    port, token = free_port(), "orientviz-test-token"
    log = tmp_path / "jupyterlab.log"
    server = lab._start_lab(root, port, token, log)
    page = browser_page
    shot = tmp_path / "jupyterlab_viewer.png"
    try:
        lab._wait_http(f"http://127.0.0.1:{port}/api/status?token={token}", server, deadline, log)
        page.set_default_timeout(lab.STEP_MS)
        page.goto(f"http://127.0.0.1:{port}/lab/tree/{LESSON}?token={token}")
        page.wait_for_function(lab._NOTEBOOK, timeout=lab._remaining_ms(deadline))
        page.wait_for_function(lab._KERNEL_IDLE, timeout=lab._remaining_ms(deadline), polling=250)
        page.evaluate("() => window.jupyterapp.commands.execute('notebook:run-all-cells')")
        page.wait_for_function(lab._ALL_RUN, timeout=lab._remaining_ms(deadline), polling=250)
        assert page.evaluate(lab._ERRORS) == [], "the lesson raised in JupyterLab"

        # the IFrame of the live viewer, inside a cell's output area
        frame_el = page.locator(".jp-OutputArea-output iframe").first
        frame_el.scroll_into_view_if_needed(timeout=lab._remaining_ms(deadline))
        src = frame_el.get_attribute("src") or ""
        assert src.startswith("http://127.0.0.1:"), f"the viewer is not served locally: {src!r}"
        viewer = page.frame_locator(".jp-OutputArea-output iframe").first
        canvas = viewer.locator("canvas").first
        canvas.wait_for(state="visible", timeout=lab._remaining_ms(deadline))
        viewer.get_by_text("Your passes").first.wait_for(timeout=lab._remaining_ms(deadline))
        viewer.get_by_text("Dials of the right projector").first.wait_for(
            timeout=lab._remaining_ms(deadline)
        )

        # the scene arrives over the websocket and is drawn (software WebGL): poll the pixels
        drawn, share, colours = False, 0.0, 0
        while time.monotonic() < deadline:
            rgb = np.asarray(Image.open(io.BytesIO(canvas.screenshot())).convert("RGB"), int)
            background = np.median(rgb.reshape(-1, 3), axis=0)
            differs = np.abs(rgb - background).sum(axis=2) > 60
            share = float(differs.mean())
            colours = len({tuple(c // 32) for c in rgb[differs][:: max(1, differs.sum() // 4000)]})
            if share > 0.01 and colours >= 4:
                drawn = True
                break
            time.sleep(1.0)
        page.screenshot(path=str(shot), full_page=False)
        assert drawn, (
            f"the viewer's canvas in the notebook stays blank: {share:.2%} of its pixels differ "
            f"from the background, {colours} colour groups (screenshot {shot})"
        )
    finally:
        lab._stop_lab(server)
