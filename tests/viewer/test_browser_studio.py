"""The design studio in a real headless Chromium: accepting the suggested control point
recolours the block and changes the summary; a real click on the canvas flies a cross
strip (more images, new colours and summary); undo takes each back."""

from __future__ import annotations

import time

import numpy as np
import pytest

from orientviz.viewer.demos import load_demo

from .browser import (
    SCENE_WIDTH,
    changed_share,
    gui_control,
    open_demo,
    scene_image,
    served,
    wait_for,
    wait_for_picture,
)

pytestmark = [pytest.mark.browser, pytest.mark.slow]


def test_design_studio_adds_a_control_point_and_a_cross_strip(browser_page, tmp_path):
    with served(load_demo("design")) as app:
        page = browser_page
        img = open_demo(page, app)
        sv = app.extra["studio"]
        st = sv.studio
        n0 = st.quality.summary["n_control"]
        cols0 = sv.colours.copy()
        assert page.get_by_text(f"{n0} control points").count() > 0
        page.get_by_role("button", name="suggest control point").click()
        assert wait_for(lambda: st.suggestion is not None, 60), "the click did not arrive"
        sug = st.suggestion
        assert wait_for(
            lambda: page.get_by_text(f"make point {sug.point_id} control").count() > 0, 60
        )
        page.get_by_role("button", name="accept suggestion").click()
        assert wait_for(lambda: len(st.log) == 1, 60), "accept did not arrive"
        q = st.quality
        assert q.summary["n_control"] == n0 + 1
        assert q.point_sigma[:, 2].max() == pytest.approx(sug.after, rel=1e-6)

        # the points' colours change on the Python side (after the redraw that follows the
        # update) and on the screen
        def recoloured():
            return np.any(np.abs(sv.colours.astype(int) - cols0.astype(int)).max(axis=1) > 40)

        assert wait_for(recoloured, 60), "the points kept their colours"
        assert wait_for(lambda: page.get_by_text(f"{n0 + 1} control points").count() > 0, 60)
        wait_for_picture(page, img, lambda a: changed_share(img, a) > 0.002, 60)
        # undo returns to the start
        page.get_by_role("button", name="undo").click()
        assert wait_for(lambda: len(st.log) == 2, 60)
        assert wait_for(lambda: page.get_by_text(f"{n0} control points").count() > 0, 60)
        time.sleep(1.5)  # the redraw after the undo
        after_undo = scene_image(page)

        # a click on the ground flies a cross strip through the clicked place
        m0, z0 = st.block.n_images, st.quality.summary["sigma_z_rms"]
        cols1 = sv.colours.copy()
        gui_control(page, "a click on the ground", "input").click()
        page.get_by_role("option", name="flies a cross strip through it").click()
        assert wait_for(lambda: sv.panel._clicking, 60), "the click mode did not arrive"
        vw = page.viewport_size
        for _ in range(6):  # the client enables scene clicks a moment after the server asks
            page.mouse.click(vw["width"] * SCENE_WIDTH * 0.5, vw["height"] * 0.5)
            if wait_for(lambda: st.block.n_images > m0, 10):
                break
        assert st.block.n_images > m0, "no canvas click arrived"
        assert st.quality.summary["sigma_z_rms"] < z0
        n_new = st.block.n_images - m0
        assert wait_for(lambda: page.get_by_text(f"(+{n_new} by cross strips").count() > 0, 60)
        assert wait_for(lambda: sv.colours.shape != cols1.shape or np.any(sv.colours != cols1), 60)
        wait_for_picture(page, after_undo, lambda a: changed_share(after_undo, a) > 0.002, 60)
        page.screenshot(path=str(tmp_path / "studio_cross_strip.png"))  # for a look when it fails
        page.get_by_role("button", name="undo").click()
        assert wait_for(lambda: st.block.n_images == m0, 60)
