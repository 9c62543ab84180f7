"""Acting on the block's adjustment in a real browser (headless Chromium): a ray switched off
in the page re-solves on the Python side, the picture answers, and undo restores the state."""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.viewer.demos import load_demo

from .browser import changed_share, served, wait_for
from .test_browser_demos import open_demo, wait_for_picture

pytestmark = [pytest.mark.browser, pytest.mark.slow]  # ~20 s with software WebGL


def test_ray_off_in_the_page_resolves_and_undo_restores(browser_page):
    with served(load_demo("block")) as app:
        page = browser_page
        img = open_demo(page, app)
        st, act = app.demo.state, app.panel.act
        page.get_by_role("button", name="run to convergence").click()
        assert wait_for(lambda: st.at_result and len(st.changes) == 2, 60), "no adjustment"
        adjusted = wait_for_picture(page, img, lambda a: changed_share(img, a) > 0.002, 60)
        before = st.changes[1]
        j = act.chosen_ray()
        page.get_by_role("button", name="ray off / on").click()
        assert wait_for(lambda: len(st.changes) == 3, 60), "the click did not re-solve"
        assert not st.edits.obs_on[j] and st.changes[2].sigma0 != before.sigma0
        wait_for_picture(page, adjusted, lambda a: changed_share(adjusted, a) > 0.0005)
        page.get_by_role("button", name="undo").click()
        assert wait_for(lambda: st.change_cursor == 1, 60), "undo did not arrive"
        with app.gate.lock:  # let the callbacks finish
            pass
        assert st.edits.obs_on[j] and st.result is before.result
        np.testing.assert_array_equal(st.block.points.xyz, before.xyz)
