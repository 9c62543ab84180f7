"""Every ``orientviz view`` demo in a real headless Chromium: it draws its elements, and an
interaction in the page changes the scene (server-side state and the pixels).

Each test opens one demo (``DEMOS``) on 127.0.0.1, waits for the page to draw, checks that
the scene part of the screenshot is not blank and holds the colours of the demo's
elements, acts in the page (a checkbox, a slider, a button, a dropdown) and polls, with a
deadline, until the Python side has followed and the picture has changed.
"""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.viewer.demos import DEMOS, load_demo

from .browser import (
    changed_share,
    colour_count,
    gui_control,
    open_demo,
    served,
    wait_for,
    wait_for_picture,
)

pytestmark = [pytest.mark.browser, pytest.mark.slow]  # ~10-20 s each with software WebGL


def drawn_with(page, colours: dict, least: int = 20) -> tuple[np.ndarray, dict]:
    """Poll screenshots until every colour of ``colours`` covers ``least`` pixels (60 s).

    Returns the screenshot and the pixel count of each colour. Under load the nodes of a
    scene arrive one by one, so a single screenshot may catch a scene half drawn.
    """
    found = {}

    def counts(a):
        found.update({k: colour_count(a, c) for k, c in colours.items()})
        return min(found.values()) >= least

    img = wait_for_picture(page, None, counts, 60)
    return img, dict(found)


def test_every_demo_has_a_browser_test():
    tested = {"block", "pair", "radar", "design"}  # design: tests/viewer/test_browser_studio.py
    assert set(DEMOS) == tested, f"demos without a browser test: {set(DEMOS) - tested}"


def test_radar_demo_draws_the_construction_and_its_checkbox_hides_it(browser_page):
    from orientviz.viewer.radar_scene import ELEMENTS

    with served(load_demo("radar")) as app:
        page = browser_page
        open_demo(page, app)
        # each element of Geier's construction is on the screen (tens to hundreds of pixels)
        keys = ("slant_range", "circle", "s_e", "target")
        img, counts = drawn_with(page, {k: ELEMENTS[k][0] for k in keys})
        rv = app.extra["radar"]
        box = page.get_by_role("checkbox", name="construction of the target (Fig. 4)")
        box.click()
        assert wait_for(lambda: rv.h["construction"].value is False, 60), "the click did not arrive"
        assert not rv.nodes["circle"].visible and not rv.nodes["ground_plane"].visible
        blue = ELEMENTS["circle"][0]
        after = wait_for_picture(
            page, img, lambda a: colour_count(a, blue) < 0.2 * counts["circle"], 60
        )
        assert changed_share(img, after) > 0.005


def test_pair_demo_draws_rays_and_gap_and_a_dial_moves_them(browser_page):
    from orientviz.units import RHO_C
    from orientviz.viewer.pair_scene import GAP, LEFT_RAY, RIGHT_RAY

    with served(load_demo("pair")) as app:
        page = browser_page
        open_demo(page, app)
        img, _ = drawn_with(page, {"left": LEFT_RAY, "right": RIGHT_RAY, "gap": GAP})
        pv = app.extra["pair"]
        gap0 = pv.point["gap_length"]
        thumb = gui_control(page, "kappa [c]", "[role=slider]")
        thumb.focus()
        for _ in range(20):
            thumb.press("ArrowRight")  # 20 steps of 1 c
        assert wait_for(lambda: abs(pv.plotter.settings[4] * RHO_C - 20.0) < 1e-6, 60), (
            f"κ on the Python side: {pv.plotter.settings[4] * RHO_C:.3f} c"
        )
        assert pv.point["gap_length"] != pytest.approx(gap0, rel=1e-6)
        wait_for_picture(page, img, lambda a: changed_share(img, a) > 0.002, 60)
        # the normalised images appear in the panel on request
        page.get_by_role("checkbox", name="normalised images").click()
        assert wait_for(lambda: pv.h["picture"].visible, 60), "the checkbox did not arrive"
        assert wait_for(lambda: page.get_by_text("epipolar lines are rows").count() > 0, 60)


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
        assert wait_for(lambda: q.key == "max_w" and q.quality is not None, 60)
        wait_for_picture(page, after_run, lambda a: changed_share(after_run, a) > 0.001, 60)
        with app.gate.lock:  # let the callbacks finish before the server stops
            pass
