"""Debugging a reconstruction by eye, in a real headless Chromium (issue 28 point 7).

Two models, each imported as a user does and viewed as a free network (``orientviz view
FILE --free``):

* the shipped BAL problem (Ladybug, 49 images, 7 776 points, 31 843 image points: a real
  SfM reconstruction; ``orientviz import-bal ladybug``);
* the shipped COLMAP model ``axe`` (52 photographs of a Bronze Age axe, CC BY 4.0:
  src/orientviz/datasets/axe/MANIFEST.json; 10 089 points, 42 727 image points after the
  import leaves out 65 repeated observations; a real SfM reconstruction with a RADIAL
  camera), read by ``orientviz import-colmap`` as a user does (COLMAP's objective, focal
  length and distortion free).

Ladybug opens as ``orientviz view`` opens it, at the file's start values while the solve
runs in the background (the page shows the start's σ0 and says so, then the solution's).
In each the scene draws, the panel shows σ̂0 of the solve and says that the precision
waits for a request (above the viewer's limit), names the file's units (model units,
degrees, pixels; no metres, gon, µm or aerial words: :func:`speaks_as_the_file`), the worst images and points by |v|/σ are
listed and the worst of each is chosen (flown to) from the page, and switching that image off re-solves and undo restores it.
"""

from __future__ import annotations

import re
import threading

import numpy as np
import pytest

from orientviz.cli import main
from orientviz.viewer.app import ViewerApp, demo_from_file
from orientviz.viewer.block_geometry import COLORS

from .browser import (
    changed_share,
    colour_count,
    gui_control,
    open_demo,
    wait_for,
    wait_for_picture,
)

pytestmark = [pytest.mark.browser, pytest.mark.slow]


@pytest.fixture(scope="module")
def ladybug_app(tmp_path_factory):
    """Opened as ``orientviz view`` opens it: at the file's start values while it is
    solved in the background (held at ``app.solve_gate`` until the test has seen the page)."""
    path = tmp_path_factory.mktemp("bal") / "ladybug.json"
    assert main(["import-bal", "ladybug", "-o", str(path)]) == 0
    demo = demo_from_file(str(path), {"free": True}, background=True)
    assert demo.background is not None  # 31 843 image points, every start value given
    gate, solve = threading.Event(), demo.background.solve
    demo.background.solve = lambda callback: gate.wait(120) and solve(callback)
    app = ViewerApp(demo, port=0, verbose=False)
    app.solve_gate = gate
    yield app
    with app.gate.lock:  # let the callbacks finish before the server stops
        pass
    app.stop()


@pytest.fixture(scope="module")
def colmap_app(tmp_path_factory):
    from orientviz.datasets.sfm import axe_model

    path = tmp_path_factory.mktemp("colmap") / "axe.json"
    assert main(["import-colmap", str(axe_model()), "-o", str(path)]) == 0
    app = ViewerApp(demo_from_file(str(path), {"free": True}), port=0, verbose=False)
    yield app
    with app.gate.lock:  # let the callbacks finish before the server stops
        pass
    app.stop()


def test_a_real_bal_model_debugged_in_the_page(module_browser, ladybug_app):
    debugged_in_the_page(module_browser, ladybug_app, (49, 7776))


def test_a_real_colmap_model_debugged_in_the_page(module_browser, colmap_app):
    debugged_in_the_page(module_browser, colmap_app, (52, 10089))


#: Words and units that have no place in the page of a reconstruction: its scale is
#: arbitrary (no m, mm, km), its pixels are not micrometres, its file's angles are degrees,
#: and it was not flown (no strips, flying height or heights above ground).
FOREIGN = re.compile(r"\b(?:m|mm|cm|km|µm|um|gon|strips?|flying|height)\b|Z up")


def speaks_as_the_file(body: str) -> None:
    """The page of an imported reconstruction (model units, pixels, degrees) names its
    units as the file does: positions in model units, angles in degrees, the residuals'
    scale bar in model units at the object and px in the image, the camera in px."""
    assert FOREIGN.findall(body) == [], FOREIGN.findall(body)
    assert "X0 [model units]" in body and "omega [deg]" in body
    assert re.search(r"bar = [\d.e+-]+ model units at the object ≈ [\d.e+-]+ px in the image", body)
    assert re.search(r"\bc = [\d.]+ .*px\b", body)  # the principal distance in pixels


def debugged_in_the_page(browser, app, size: tuple[int, int]) -> None:
    """Colours by |v|/σ, the worst image chosen in the page and flown to, off and undo."""
    page = browser.new_page()
    st, q = app.panel.state, app.panel.quality
    b = st.block
    assert (b.n_images, b.n_points) == size and not app.messages
    img = open_demo(page, app, min_drawn=0.004)
    # the first view shows the cameras as frustums, not dots (the scene's 0.1 %; a view
    # that frames only the points or frustums sized for an aerial block: 0–150 px)
    frustums = colour_count(img, COLORS["frustum"])
    assert frustums > 0.001 * img.shape[0] * img.shape[1], f"frustums hardly seen: {frustums} px"
    if getattr(app, "solve_gate", None) is not None:  # opened while the solve runs
        start = f"{st.history[0].sigma0:.10g}"
        body = page.inner_text("body")
        assert "solving in the background" in body and start in body
        assert app.background._hold_until > 0  # the page's connection held the solve
        app.solve_gate.set()
        assert app.background.wait(300)
        solution = f"{app.demo.solution.adjustment.sigma0:.10g}"
        assert wait_for(lambda: solution in page.inner_text("body"), 60)
        assert "solving in the background" not in page.inner_text("body")
        img = wait_for_picture(page, img, lambda a: changed_share(img, a) > 0.0005, 60)
    sigma0 = f"{app.demo.solution.adjustment.sigma0:.10g}"
    body = page.inner_text("body")
    assert sigma0 in body and "precision not computed" in body
    speaks_as_the_file(body)
    # the worst images by |v|/σ: choose the measure, then the worst image in the page
    gui_control(page, "colour by", "input").click()
    page.get_by_role("option", name="RMS of residuals |v|/σ (no precision needed)").click()
    assert wait_for(lambda: q.key == "rms_v" and len(q.worst_images) == 10, 60)
    worst = q.worst_images[0]
    assert q.quality.image[worst] == np.nanmax(q.quality.image)
    # the points and frustums take the colours (small on the screen: ~0.05 % of the pixels)
    coloured = wait_for_picture(page, img, lambda a: changed_share(img, a) > 0.0003, 60)
    gui_control(page, "worst images", "input").click()
    page.get_by_role("option", name=f"1. {b.images.ids[worst]} ").click()
    assert wait_for(lambda: app.scene.selected == worst, 60), "the choice did not fly there"
    # act: the worst image off re-solves (σ̂0 changes), undo restores the solve's state
    page.get_by_role("button", name="selected image off / on").click()
    assert wait_for(lambda: len(st.changes) == 2, 120), "the click did not re-solve"
    assert not st.edits.image_on[worst] and st.result.sigma0 != pytest.approx(float(sigma0))
    wait_for_picture(page, coloured, lambda a: changed_share(coloured, a) > 0.0005, 60)
    page.get_by_role("button", name="undo").click()
    assert wait_for(lambda: st.change_cursor == 0, 60), "undo did not arrive"
    with app.gate.lock:
        pass
    assert st.edits.image_on[worst] and f"{st.result.sigma0:.10g}" == sigma0
    # the worst points: the first entry is the point of the largest |v|/σ, chosen in the page
    point = q.worst_points[0]
    assert q.quality.point[point] == np.nanmax(q.quality.point)
    gui_control(page, "worst points", "input").click()
    page.get_by_role("option", name=f"1. {b.points.ids[point]} ").click()
    assert wait_for(lambda: app.scene.selected_point == point, 60), "the point was not chosen"
    with app.gate.lock:  # the flight to it has ended before the page goes
        pass
    page.close()
