"""The viewer on the shipped data sets, in a real headless Chromium (issue 31, points 2, 7, 9).

* every shipped data set opens to a non-blank scene with the solve's σ̂0 in the panel;
* the residual vectors keep their scale while the block converges: drawn alone, they
  cover far fewer pixels after "run to convergence" than before, and the scale bar's
  text stays the same;
* nothing the page loads comes from beyond 127.0.0.1, and the share button is off.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from orientviz.io.datasets import list_datasets
from orientviz.io.solve import load_named, solve_problem

from .browser import drawn_share, gui_control, open_demo, scene_image, served, wait_for

pytestmark = [pytest.mark.browser, pytest.mark.slow]


def panel_text(page) -> str:
    return page.inner_text("body")


#: shipped data sets whose solution has no points to draw: the panel only (σ̂0, report)
PANEL_ONLY = ("pair_example", "fig7_calibration_problem")


def test_every_shipped_data_set_opens_with_its_sigma0(module_browser):
    """Every shipped data set (DBAT blocks, examples, Geier's problems) in one browser, a
    page each: the scene is not blank (but for the two without points), the solve's σ̂0
    is in the panel, no message, no "strip -1"."""
    names = list_datasets()
    assert {"block_strip", "dbat_sxb", "dbat_camcal", "similarity_example"} <= set(names)
    failures = []
    for name in names:
        sigma0 = solve_problem(load_named(name)).adjustment.sigma0
        page = module_browser.new_page()
        with served(name) as app:
            try:
                if name in PANEL_ONLY:
                    page.goto(app.url)
                    page.wait_for_selector("canvas", timeout=60_000)
                else:
                    open_demo(page, app, min_drawn=0.002)
            except AssertionError as exc:
                failures.append(f"{name}: {exc}")
                page.close()
                continue
            shown = f"{sigma0:.10g}"
            if not wait_for(lambda s=shown, p=page: s in panel_text(p), 20):
                failures.append(f"{name}: σ̂0 {shown} not in the panel")
            if app.messages:
                failures.append(f"{name}: messages {app.messages}")
            if "strip -1" in panel_text(page):
                failures.append(f"{name}: 'strip -1' in the panel")
        page.close()
    assert not failures, "\n".join(failures)


def residual_pixels(page, before=None) -> float:
    img = scene_image(page)
    return drawn_share(img)


def test_residual_vectors_shrink_at_a_fixed_scale(module_browser):
    """The block demo from its approximations: only the residual vectors drawn; after
    "run to convergence" they cover a fraction of the pixels, at the same scale."""
    page = module_browser.new_page()
    with served("block") as app:
        open_demo(page, app)
        scene = app.scene
        for key in ("frustums", "points", "strips", "ellipsoids"):
            scene.set_visible(key, False)
        scene.set_rays("none")
        scene.nodes["labels/scale_bar"].visible = False
        k0, text0 = scene.exaggeration, scene.scale_bar_text
        time.sleep(2.0)
        before = residual_pixels(page)
        assert before > 0.002, f"the residual vectors are not drawn ({before:.4f})"
        page.get_by_role("button", name="run to convergence").click()
        assert wait_for(lambda: app.demo.state.result is not None, 120)
        assert wait_for(lambda: residual_pixels(page) < 0.5 * before, 60), (
            f"the vectors did not shrink: {before:.4f} → {residual_pixels(page):.4f}"
        )
        assert scene.exaggeration == k0 and scene.scale_bar_text == text0
        # re-scaling happens on request only
        page.get_by_role("button", name="fit the residual scale to this state").click()
        assert wait_for(lambda: scene.exaggeration > 2 * k0, 30)
        assert wait_for(lambda: residual_pixels(page) > 0.5 * before, 60)


def test_nothing_beyond_localhost_and_no_share_button(module_browser, monkeypatch):
    import socket

    contacted = []
    real_connect = socket.socket.connect

    def connect(self, address):
        host = address[0] if isinstance(address, tuple) else str(address)
        if host not in ("127.0.0.1", "::1", "localhost") and not str(host).startswith("/"):
            contacted.append(address)
        return real_connect(self, address)

    monkeypatch.setattr(socket.socket, "connect", connect)
    page = module_browser.new_page()
    requests = []
    page.on("request", lambda r: requests.append(r.url))
    with served("dbat_sxb") as app:
        assert app.host == "127.0.0.1"
        open_demo(page, app)
        gui_control(page, "X0 [m]").focus()
        page.keyboard.press("ArrowRight")
        time.sleep(1.0)
        # viser's share button is an icon button with tabler's "share" icon
        assert page.locator(".tabler-icon-adjustments").count() == 1  # the panel's icons drew
        assert page.locator(".tabler-icon-share").count() == 0
        assert app.server.request_share_url() is None  # a share request is refused
    outside = [u for u in requests if not u.startswith(("http://127.0.0.1", "ws://127.0.0.1",
                                                        "data:", "blob:"))]  # fmt: skip
    assert not outside, f"the page loaded from beyond 127.0.0.1: {outside[:5]}"
    assert not contacted, f"the server connected beyond 127.0.0.1: {contacted}"
    assert np.isfinite(app.demo.state.sigma0())
