"""The design studio in a real headless Chromium: accepting the suggested control point
recolours the block and changes the summary."""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.viewer.demos import load_demo

from .browser import changed_share, open_demo, served, wait_for, wait_for_picture

pytestmark = [pytest.mark.browser, pytest.mark.slow]


def test_design_studio_adds_a_control_point_and_recolours(browser_page):
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
        assert wait_for(lambda: len(st.live.changes) == 1, 60), "accept did not arrive"
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
        assert wait_for(lambda: len(st.live.changes) == 0, 60)
        assert wait_for(lambda: page.get_by_text(f"{n0} control points").count() > 0, 60)
