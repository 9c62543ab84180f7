"""Every ``orientviz view`` demo in a real headless Chromium: it draws its elements, and an
interaction in the page changes the scene (server-side state and the pixels).

Each test opens one demo (``DEMOS``) on 127.0.0.1, waits for the page to draw, checks that
the scene part of the screenshot is not blank and holds the colours of the demo's
elements, acts in the page (a checkbox, a slider, a button, a dropdown) and polls, with a
deadline, until the Python side has followed and the picture has changed.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from orientviz.viewer.demos import DEMOS, load_demo

from .browser import (
    changed_share,
    colour_count,
    drawn_share,
    gui_control,
    scene_image,
    served,
    wait_for,
)

pytestmark = [pytest.mark.browser, pytest.mark.slow]  # ~10-20 s each with software WebGL


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


def wait_for_picture(page, before: np.ndarray, test, timeout: float = 30.0) -> np.ndarray:
    """Poll screenshots until ``test(after)`` holds; return the last one."""
    shot = {}

    def ok():
        shot["img"] = scene_image(page)
        return test(shot["img"])

    assert wait_for(ok, timeout, 0.5), (
        f"the picture did not change as expected ({changed_share(before, shot['img']):.4f} changed)"
    )
    return shot["img"]


def test_every_demo_has_a_browser_test():
    tested = {"block", "pair", "radar"}
    assert set(DEMOS) == tested, f"demos without a browser test: {set(DEMOS) - tested}"


def test_radar_demo_draws_the_construction_and_its_checkbox_hides_it(browser_page):
    from orientviz.viewer.radar_scene import ELEMENTS

    with served(load_demo("radar")) as app:
        page = browser_page
        img = open_demo(page, app)
        counts = {
            k: colour_count(img, ELEMENTS[k][0]) for k in ("slant_range", "circle", "s_e", "target")
        }
        # each element of Geier's construction is on the screen (tens to hundreds of pixels)
        assert min(counts.values()) >= 20, counts
        rv = app.extra["radar"]
        box = page.get_by_role("checkbox", name="construction of the target (Fig. 4)")
        box.click()
        assert wait_for(lambda: rv.h["construction"].value is False), "the click did not arrive"
        assert not rv.nodes["circle"].visible and not rv.nodes["ground_plane"].visible
        blue = ELEMENTS["circle"][0]
        after = wait_for_picture(
            page, img, lambda a: colour_count(a, blue) < 0.2 * counts["circle"]
        )
        assert changed_share(img, after) > 0.005


def test_pair_demo_draws_rays_and_gap_and_a_dial_moves_them(browser_page):
    from orientviz.units import RHO_C
    from orientviz.viewer.pair_scene import GAP, LEFT_RAY, RIGHT_RAY

    with served(load_demo("pair")) as app:
        page = browser_page
        img = open_demo(page, app)
        counts = {n: colour_count(img, c) for n, c in
                  (("left", LEFT_RAY), ("right", RIGHT_RAY), ("gap", GAP))}  # fmt: skip
        assert min(counts.values()) >= 20, counts
        pv = app.extra["pair"]
        gap0 = pv.point["gap_length"]
        thumb = gui_control(page, "kappa [c]", "[role=slider]")
        thumb.focus()
        for _ in range(20):
            thumb.press("ArrowRight")  # 20 steps of 1 c
        assert wait_for(lambda: abs(pv.plotter.settings[4] * RHO_C - 20.0) < 1e-6), (
            f"κ on the Python side: {pv.plotter.settings[4] * RHO_C:.3f} c"
        )
        assert pv.point["gap_length"] != pytest.approx(gap0, rel=1e-6)
        wait_for_picture(page, img, lambda a: changed_share(img, a) > 0.002)
        # the normalised images appear in the panel on request
        page.get_by_role("checkbox", name="normalised images").click()
        assert wait_for(lambda: pv.h["picture"].visible), "the checkbox did not arrive"
        assert wait_for(lambda: page.get_by_text("epipolar lines are rows").count() > 0)


def test_block_demo_converges_and_colours_by_quality(browser_page):
    with served(load_demo("block")) as app:
        page = browser_page
        img = open_demo(page, app)
        st = app.demo.state
        page.get_by_role("button", name="run to convergence").click()
        assert wait_for(lambda: st.at_result and len(st.history) > 2, 60), "no adjustment"
        after_run = wait_for_picture(page, img, lambda a: changed_share(img, a) > 0.002, 60)
        # colour by quality: choose a measure in the dropdown
        q = app.panel.quality
        gui_control(page, "colour by", "input").click()
        page.get_by_role("option", name="largest normalised residual |w|").click()
        assert wait_for(lambda: q.key == "max_w" and q.quality is not None, 30)
        wait_for_picture(page, after_run, lambda a: changed_share(after_run, a) > 0.001)
        with app.panel._lock:  # let the callbacks finish before the server stops
            pass
