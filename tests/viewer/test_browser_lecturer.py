"""What a lecturer takes away, in a real headless Chromium (issue 31 point 8): the button
"save the view as PNG (with legend)" downloads the view as the browser draws it with the
legend and σ̂0 beside it."""

from __future__ import annotations

import io

import numpy as np
import pytest

from orientviz.viewer.block_geometry import COLORS
from orientviz.viewer.snapshot import LEGEND_WIDTH

from .browser import colour_count, open_demo, served

pytestmark = [pytest.mark.browser, pytest.mark.slow]


def test_save_the_view_as_png_with_its_legend(module_browser, tmp_path):
    from PIL import Image

    page = module_browser.new_page()
    with served("dbat_camcal") as app:
        open_demo(page, app, min_drawn=0.004)
        with page.expect_download(timeout=120_000) as dl:
            page.get_by_role("button", name="save the view as PNG (with legend)").click()
        path = tmp_path / "view.png"
        dl.value.save_as(path)
        assert dl.value.suggested_filename == "orientviz-view.png"
        img = np.asarray(Image.open(io.BytesIO(path.read_bytes())).convert("RGB"), float)
        sigma0 = f"{app.panel.state.sigma0():.10g}"
    assert img.shape[1] == 1000 + LEGEND_WIDTH and img.shape[0] >= 800
    view, legend = img[:, :1000], img[:, 1000:]
    assert np.median(view.reshape(-1, 3), axis=0).tolist() == [255.0, 255.0, 255.0]
    assert np.mean(np.abs(view - 255).sum(axis=2) > 60) > 0.01  # the scene is drawn
    # the legend's symbols in their colours: the residuals' green square, the control diamond
    assert colour_count(legend, (40, 160, 80)) > 5
    assert colour_count(legend, COLORS["control"]) > 5
    assert sigma0 in app.panel.handles["stats"].content
    page.close()
