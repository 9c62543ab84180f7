"""Regenerate the two pictures at the top of README.md.

    python tools/make_readme_figures.py            # both
    python tools/make_readme_figures.py --only lesson

* ``docs/figures/viewer.png``: the 3D viewer on its default demo (what ``orientviz view``
  shows), served on 127.0.0.1 and photographed in headless Chromium (playwright with
  /usr/bin/chromium and the test suite's Chromium flags; software WebGL).
* ``docs/figures/lesson_block_errors.png``: the figure of lesson 08 that sets the
  polynomial method beside independent models (true errors of the tie points), made
  with :func:`orientviz.plot.block.plot_error_vectors` on the lesson's own block.

Both are written as palette PNGs and must stay under 400 KB (checked here).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import io
import pathlib
import shutil
import socket
import tempfile
import time
from collections.abc import Iterator
from typing import Any

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "figures"
MAX_BYTES = 400_000


def _chromium_settings() -> tuple[str, list[str]]:
    """Chromium path and flags from tests/conftest.py (the one place that lists them)."""
    spec = importlib.util.spec_from_file_location(
        "_orientviz_conftest", ROOT / "tests" / "conftest.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.CHROMIUM, list(mod.CHROMIUM_FLAGS)


def _save_png(image, path: pathlib.Path, colours: int = 256) -> None:
    """Write a PIL image as an optimised palette PNG and check its size."""
    from PIL import Image

    rgb = image.convert("RGB")
    small = rgb.quantize(colors=colours, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    small.save(path, optimize=True)
    size = path.stat().st_size
    if size > MAX_BYTES:
        raise SystemExit(f"{path} is {size / 1000:.0f} KB (> {MAX_BYTES / 1000:.0f} KB)")
    print(f"wrote {path} ({image.width} x {image.height} px, {size / 1000:.0f} KB)")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


VIEWPORT = (1400, 820)  # CSS px of the screenshot


def _frame_camera(camera, zoom: float, panel: float) -> None:
    """Move the camera ``zoom`` times as far from its target, then sideways by ``panel``
    half-widths of the view, so that the scene sits left of the GUI panel."""
    look = np.asarray(camera.look_at, dtype=float)
    pos = np.asarray(camera.position, dtype=float)
    pos = look + zoom * (pos - look)
    forward = (look - pos) / np.linalg.norm(look - pos)
    right = np.cross(forward, np.asarray(camera.up_direction, dtype=float))
    right /= np.linalg.norm(right)
    half_width = np.linalg.norm(look - pos) * np.tan(camera.fov / 2) * camera.aspect
    shift = panel * half_width * right
    camera.position, camera.look_at = pos + shift, look + shift


@contextlib.contextmanager
def viewer_page(
    content: Any, viewport: tuple[int, int] = VIEWPORT, settle_s: float = 5.0
) -> Iterator[tuple[Any, Any]]:
    """The viewer on ``content`` (served on 127.0.0.1) in a headless Chromium page, drawn.

    Yields ``(app, page)`` once the page is connected and the scene has had ``settle_s``
    seconds to arrive (software WebGL); stops the server and the browser afterwards.
    """
    from playwright.sync_api import sync_playwright

    from orientviz.viewer.app import ViewerApp

    chromium, flags = _chromium_settings()
    app = ViewerApp(content, host="127.0.0.1", port=_free_port(), verbose=False)
    profile = tempfile.mkdtemp(prefix="orientviz-figure-chromium-")
    try:
        with sync_playwright() as p:
            context = p.chromium.launch_persistent_context(
                profile, executable_path=chromium, headless=True, args=flags,
                viewport={"width": viewport[0], "height": viewport[1]},
            )  # fmt: skip
            try:
                page = context.new_page()
                page.goto(app.url)
                page.wait_for_selector("canvas", timeout=60_000)
                deadline = time.monotonic() + 60
                while not app.server.get_clients() and time.monotonic() < deadline:
                    time.sleep(0.1)
                # the "software WebGL" notice is about this headless machine, not the viewer
                page.add_style_tag(content=".mantine-Notifications-root {display: none}")
                time.sleep(settle_s)  # the scene arrives and is drawn
                yield app, page
            finally:
                context.close()
    finally:
        app.stop()
        shutil.rmtree(profile, ignore_errors=True)


def viewer_figure(
    path: pathlib.Path,
    *,
    zoom: float = 0.72,
    shift: float = 0.12,
    converge: bool = True,
    settle_s: float = 5.0,
) -> None:
    """Screenshot of the viewer on the default demo, optionally after "run to convergence"."""
    from PIL import Image

    from orientviz.viewer.app import DEFAULT_DEMO

    with viewer_page(DEFAULT_DEMO, settle_s=settle_s) as (app, page):
        for client in app.server.get_clients().values():
            _frame_camera(client.camera, zoom, shift)
        if converge:
            page.get_by_role("button", name="run to convergence").click()
        time.sleep(settle_s)
        png = page.screenshot()
    image = Image.open(io.BytesIO(png))
    rgb = np.asarray(image.convert("RGB"), dtype=float)
    if rgb.std() < 10:
        raise SystemExit("the viewer screenshot is blank")
    _save_png(image, path)


def lesson_figure(path: pathlib.Path) -> None:
    """Lesson 08: true errors of the tie points, polynomial method vs independent models."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from PIL import Image

    from orientviz.block import TIE
    from orientviz.plot.block import plot_error_vectors
    from orientviz.polynomial import polynomial_adjust
    from orientviz.simulate import simulate_block
    from orientviz.stereo_models import independent_models

    # the lesson's block: 3 strips of 8 images, control chains every 4 bases
    sim = simulate_block(3, 8, rng=np.random.default_rng(5), extra=None,
                         control="chains", control_spacing=4, chain_spacing=4)  # fmt: skip
    poly = polynomial_adjust(sim.block, degree_xy=3, degree_z=3).points
    models = independent_models(sim.block).points
    fig, axs = plt.subplots(1, 2, figsize=(13, 4.5))
    same = dict(control=sim.block.points.role != TIE, zlim=1.5, exaggeration=5000)
    plot_error_vectors(poly, sim.truth.points.xyz, ax=axs[0],
                       title="polynomial method (arrows ×5000)", **same)  # fmt: skip
    plot_error_vectors(models, sim.truth.points.xyz, ax=axs[1],
                       title="independent models, 7 parameters (arrows ×5000)", **same)  # fmt: skip
    buf = io.BytesIO()
    fig.savefig(buf, dpi=100, bbox_inches="tight", facecolor="white")
    plt.close(fig)
    _save_png(Image.open(buf), path)


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--only", choices=["viewer", "lesson"], default=None)
    args = p.parse_args(argv)
    OUT.mkdir(parents=True, exist_ok=True)
    if args.only in (None, "viewer"):
        viewer_figure(OUT / "viewer.png")
    if args.only in (None, "lesson"):
        lesson_figure(OUT / "lesson_block_errors.png")


if __name__ == "__main__":
    main()
