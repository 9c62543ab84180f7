"""Photograph every ``orientviz view`` demo for the book's viewer chapter and the README.

    python tools/make_viewer_screenshots.py              # all demos
    python tools/make_viewer_screenshots.py --only radar

Each demo is served on 127.0.0.1 and opened in headless Chromium (playwright with
/usr/bin/chromium and the test suite's flags, software WebGL); a short scenario puts it in
a telling state (block: run to convergence, the residual scale fitted anew, colour by the
largest normalised residual; pair: the rays, gap and epipolar plane of point 5 with the
normalised images; radar: Geier's construction of target 15 in image 3 with the legend;
dbat_camcal: the shipped DBAT camera calibration as ``orientviz solve`` solves it, with
the estimated camera, its distortion field and the legend; axe: the shipped COLMAP model
imported and solved ``--free``, coloured by |v|/σ, in model units, degrees and pixels).
Written to ``book/_static/viewer/<demo>.png`` as palette PNGs (helpers of
``make_readme_figures.py``: at most 400 KB each, checked).
"""

from __future__ import annotations

import argparse
import io
import pathlib
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import make_readme_figures as mrf  # noqa: E402  (the Chromium settings and the PNG writer)

OUT = mrf.ROOT / "book" / "_static" / "viewer"
VIEWPORT = (1280, 960)


def _wait(predicate: Callable[[], bool], timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise SystemExit("the viewer did not reach the state of the screenshot")
        time.sleep(0.1)


def _collapse(page: Any, *folders: str) -> None:
    """Fold GUI folders (click their titles) so that the panel shows what matters."""
    for name in folders:
        page.get_by_text(name, exact=True).first.click(timeout=120_000, force=True)
        time.sleep(0.5)  # the panel's layout settles before the next title is found


def block_scenario(app: Any, page: Any) -> None:
    """Run to convergence, colour by the largest |w| (the worst images listed)."""
    st, q = app.demo.state, app.panel.quality
    page.get_by_role("button", name="run to convergence").click()
    _wait(lambda: st.at_result and len(st.history) > 2)
    with app.panel._lock:  # the scale stays fixed while iterating; fitted anew here
        app.panel.set_exaggeration(auto=True)
    with app.panel._lock:
        q.handles["measure"].value = "largest normalised residual |w|"
    _wait(lambda: q.quality is not None)
    _collapse(page, "Image orientation", "Adjustment", "Largest residuals", "Display")


def camcal_scenario(app: Any, page: Any) -> None:
    """The solved calibration: legend, camera terms and the distortion of image 1."""
    _collapse(page, "Image orientation", "Adjustment", "Largest residuals", "Display",
              "Colour by quality", "Precision", "Act on the adjustment")  # fmt: skip
    app.panel.scene.set_visible("ellipsoids", False)
    app.panel.update_legend()


def axe_scenario(app: Any, page: Any) -> None:
    """The shipped COLMAP model axe as imported: coloured by |v|/σ, the panel in model
    units, degrees and pixels (the orientation folder and the legend open)."""
    q = app.panel.quality
    with app.panel._lock:
        q.handles["measure"].value = "RMS of residuals |v|/σ (no precision needed)"
    _wait(lambda: q.quality is not None)
    _collapse(page, "Adjustment", "Largest residuals", "Display", "Act on the adjustment")
    page.get_by_text("Legend", exact=True).first.scroll_into_view_if_needed()  # panel's top
    time.sleep(0.5)


def axe_content() -> Any:
    """``orientviz import-colmap`` of the shipped model axe, solved with ``--free``."""
    import contextlib
    import io
    import tempfile

    from orientviz.cli import main
    from orientviz.datasets.sfm import axe_model
    from orientviz.viewer.app import demo_from_file

    path = pathlib.Path(tempfile.mkdtemp(prefix="orientviz-axe-")) / "axe.json"
    with contextlib.redirect_stdout(io.StringIO()):
        if main(["import-colmap", str(axe_model()), "-o", str(path)]) != 0:
            raise SystemExit("import-colmap of the shipped model axe failed")
    return demo_from_file(str(path), {"free": True})


def pair_scenario(app: Any, page: Any) -> None:
    """Point 5 selected (rays, gap, epipolar plane) and the normalised images shown."""
    pv = app.extra["pair"]
    pv.h["normalised"].value = True
    _wait(lambda: pv.h["picture"].visible)
    _collapse(page, "Passes", "Display")


def radar_scenario(app: Any, page: Any) -> None:
    """The default state: image 3, target 15, construction and legend."""


SCENARIOS: dict[str, Callable[[Any, Any], None]] = {
    "block": block_scenario,
    "pair": pair_scenario,
    "radar": radar_scenario,
    "dbat_camcal": camcal_scenario,
    "axe": axe_scenario,
}
#: Scenarios whose content is not a demo name: how to make it.
CONTENT: dict[str, Callable[[], Any]] = {"axe": axe_content}


def screenshot(name: str, path: pathlib.Path, settle_s: float = 5.0) -> None:
    """Serve demo ``name``, play its scenario in Chromium and save the screenshot."""
    from PIL import Image

    from orientviz.viewer.app import resolve_content

    content = CONTENT[name]() if name in CONTENT else resolve_content(name)
    with mrf.viewer_page(content, VIEWPORT, settle_s) as (app, page):
        SCENARIOS[name](app, page)
        time.sleep(settle_s)
        png = page.screenshot()
    image = Image.open(io.BytesIO(png))
    if np.asarray(image.convert("RGB"), dtype=float).std() < 10:
        raise SystemExit(f"the screenshot of {name!r} is blank")
    mrf._save_png(image, path)


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--only", choices=sorted(SCENARIOS), default=None)
    args = p.parse_args(argv)
    OUT.mkdir(parents=True, exist_ok=True)
    for name in SCENARIOS if args.only is None else [args.only]:
        screenshot(name, OUT / f"{name}.png")


if __name__ == "__main__":
    main()
