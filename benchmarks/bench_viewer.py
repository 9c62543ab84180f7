"""Viewer performance: scene build of a 2 100-image block, slider redraw on a 200-image block.

Goals (issue 7): the 2 100-image block (all frustums, ~40 000 points, ~110 000 residual
vectors) builds in < 3 s; a slider change on a 200-image block re-projects and redraws
in < 100 ms. Printed, never asserted.

Peers in the same run:
* build — the same block drawn the naive way, one viser line-segment node per image for
  its rays (what batching avoids); only the ray nodes are timed, on a fresh server.
* slider — a full rebuild of the residual, ray and frustum nodes after the change
  (``scene.update()`` with all images) against the incremental update of one image.

With ``--browser`` it also times the round trip in headless Chromium (/usr/bin/chromium):
an arrow-key press on the ω slider of the 200-image block until the Python side has
redrawn (includes the websocket and the browser's event handling). In headless Chromium
with software WebGL (swiftshader) on a loaded machine this is dominated by the browser
rendering the scene, not by orientviz; compare it with the Python-side redraw.

Run:  PYTHONPATH=src python benchmarks/bench_viewer.py [--repeat 5] [--browser]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np


def timed(fn, repeat: int = 1) -> tuple[float, object]:
    best, out = float("inf"), None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def browser_round_trip(app, moves: int) -> float:
    """Median seconds from an arrow key on the ω slider to the Python-side redraw."""
    import shutil
    import tempfile

    from playwright.sync_api import sync_playwright

    flags = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync",
             "--use-angle=swiftshader", "--enable-unsafe-swiftshader"]  # fmt: skip
    profile = tempfile.mkdtemp(prefix="orientviz-bench-")
    h = app.panel.handles["omega"]
    out = []
    try:
        with sync_playwright() as p:
            ctx = p.chromium.launch_persistent_context(
                profile, executable_path="/usr/bin/chromium", headless=True, args=flags
            )
            page = ctx.new_page()
            page.goto(app.url)
            page.wait_for_selector("[role=slider]", timeout=60_000)
            time.sleep(2.0)
            row = page.locator("div", has=page.locator("label", has_text="omega [gon]"))
            thumb = (
                row.filter(has=page.locator("[role=slider]")).last.locator("[role=slider]").first
            )
            thumb.focus()
            for j in range(moves):
                before = h.value
                key = "ArrowRight" if j % 2 == 0 else "ArrowLeft"
                t = time.perf_counter()
                thumb.press(key)
                while h.value == before and time.perf_counter() - t < 10:
                    time.sleep(0.0005)
                out.append(time.perf_counter() - t)
            ctx.close()
    finally:
        shutil.rmtree(profile, ignore_errors=True)
    return statistics.median(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--moves", type=int, default=30)
    ap.add_argument("--browser", action="store_true", help="also time the browser round trip")
    a = ap.parse_args()

    import viser

    from orientviz.simulate import simulate_block
    from orientviz.units import to_rad
    from orientviz.viewer.app import ViewerApp
    from orientviz.viewer.block_geometry import BlockGeometry
    from orientviz.viewer.demos import demo_from_block
    from orientviz.viewer.scene import BlockScene
    from orientviz.viewer.state import BlockState

    rows: list[tuple[str, str, float, str]] = []

    # ---------------------------------------------------------------- build, 2 100 images
    t_sim, sim = timed(lambda: simulate_block(30, 70, rng=1))
    block = sim.block
    print(f"# block: {block.summary()} (simulated in {t_sim:.2f} s)")

    def geometry_only():
        st = BlockState(block)
        geo = BlockGeometry(st)
        k = geo.auto_exaggeration()
        geo.frustum_poses(), geo.points_by_role(), geo.rays(), geo.residuals(k)
        geo.strip_lines(), geo.model_outlines()
        return geo

    t_geo, _ = timed(geometry_only, a.repeat)
    rows.append(("build 2100", "geometry arrays (no viser)", t_geo, ""))

    builds = []
    for _ in range(a.repeat):
        server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
        t = time.perf_counter()
        st = BlockState(block)
        sc = BlockScene(server.scene, BlockGeometry(st)).build()
        builds.append(time.perf_counter() - t)
        n_res = np.asarray(sc.nodes["residuals"].points).shape[0]
        server.stop()
    t_build = min(builds)
    rows.append(
        (
            "build 2100",
            "orientviz scene, all nodes (Python side)",
            t_build,
            f"{n_res} residual vectors",
        )
    )

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    geo = BlockGeometry(BlockState(block))
    o = block.observations
    order = np.argsort(o.image, kind="stable")
    starts = np.searchsorted(o.image[order], np.arange(block.n_images + 1))
    rays = geo.rays()[order].astype(np.float32)

    def per_image_nodes():
        for i in range(block.n_images):
            server.scene.add_line_segments(
                f"/naive/rays/image_{i}", rays[starts[i] : starts[i + 1]], (120, 150, 200),
                thickness=1.0, thickness_units="screen",
            )  # fmt: skip

    t_naive, _ = timed(per_image_nodes, 1)
    server.stop()
    rows.append(("build 2100", "peer: rays as one node per image", t_naive, "rays only"))
    t_batched_rays, _ = timed(lambda: geo.rays(), a.repeat)
    rows.append(("build 2100", "orientviz: all rays, one node (arrays)", t_batched_rays, ""))

    # ---------------------------------------------------------------- slider, 200 images
    sim2 = simulate_block(10, 20, rng=1)
    demo = demo_from_block(sim2.block)
    app = ViewerApp(demo, port=0, verbose=False)
    try:
        p = app.panel
        p.handles["image"].value = 57
        times = []
        for j in range(a.moves):
            p.handles["omega"].value = round(0.01 * ((j % 20) + 1), 2)  # a slider move, gon
            times.append(p.last_redraw_s)
        st = demo.state
        full = []
        for _ in range(a.moves):
            t = time.perf_counter()
            st.set_exterior(57, angles=st.block.images.angles[57] + [to_rad(0.01, "gon"), 0, 0])
            app.scene.update()
            full.append(time.perf_counter() - t)
        if a.browser:
            rows.append(
                (
                    "slider 200",
                    "browser: key press → Python redraw (median)",
                    browser_round_trip(app, a.moves),
                    "",
                )
            )
    finally:
        app.stop()
    med, worst = statistics.median(times), max(times)
    rows.append(
        (
            "slider 200",
            "orientviz: one image (median)",
            med,
            f"max {worst * 1000:.1f} ms, {a.moves} moves",
        )
    )
    rows.append(
        ("slider 200", "peer: full redraw of all nodes (median)", statistics.median(full), "")
    )

    print(f"{'task':12s} {'what':46s} {'seconds':>9s}  note")
    for task, what, t, note in rows:
        print(f"{task:12s} {what:46s} {t:9.4f}  {note}")
    print(
        f"# build 2100: {t_build:.2f} s (goal < 3 s); naive per-image ray nodes / batched build = {t_naive / t_build:.2f}"
    )
    print(
        f"# slider 200: median {med * 1000:.1f} ms (goal < 100 ms); full redraw / incremental = {statistics.median(full) / med:.2f}"
    )


if __name__ == "__main__":
    main()
