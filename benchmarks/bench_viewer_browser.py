"""The viewer as a user meets it in a browser: first picture of a data set, a radar cap change.

Headless Chromium (/usr/bin/chromium, the test suite's flags: software WebGL, no GPU), a
1280 × 800 window. Each measurement runs in a fresh process of the tree given by
``--tree`` (its ``src`` on PYTHONPATH), so two trees can be compared in one run
(``--tree A --tree B``: alternated, ``--repeat`` times each; the ratio B/A is printed).

* ``open NAME [--free]`` — ``orientviz view NAME`` as a user starts it: from the start of
  the process (imports, solve, scene build: ``ViewerApp``) to the page's first picture
  (more than 1 % of the scene area drawn) and to the settled picture (two screenshots
  0.5 s apart that differ in < 0.01 % of the pixels). Printed: process (s) to the
  server ready, browser (s) from the page load to the first and the settled picture, and
  the total. CPU of the Python process is printed too (the browser's is not included).
  A large imported model opens at its start values while it is solved in the background
  (as ``orientviz view`` does): then also ``solved_s``, from the start of the process to
  the solution's settled picture, and ``solved_cpu_s``, the process's CPU until then.
* ``slide NAME`` — as ``open``, then the ω slider of the selected image moved by 1 gon and
  back on the Python side (as the GUI does) until the picture has changed and settled
  (seconds, median of the two): the redraw of a block as the browser shows it.
* ``cap`` — the radar demo: the *sphere cap* slider set to 30° then 10° on the Python side
  (as the GUI does) until the picture has changed and settled (seconds, median of the two;
  the settled picture needs two grabs 0.5 s apart, so this is ~1 s above the change
  itself); ``cap_first_s``: until the first changed picture (grabbing without pause), and
  ``toggle_first_s`` the same for a one-node change (the projection circles shown or
  hidden): the page's floor.

The screenshots polled here make the software renderer draw frames and so slow the page they
time; the first picture of ``orientviz view`` as a user waits for it is measured without them
by ``bench_viewer_command.py``.

Run:  python benchmarks/bench_viewer_browser.py open dbat_roma --tree .
      python benchmarks/bench_viewer_browser.py cap --tree /path/to/old --tree . --repeat 2
Never asserted; report the command and ``uptime`` with the numbers.
"""

from __future__ import annotations

import argparse
import io
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--use-angle=swiftshader", "--enable-unsafe-swiftshader"]  # fmt: skip
WINDOW = (1280, 800)
SCENE = 0.72  # share of the window width left of the GUI panel


def _grab(page):
    import numpy as np
    from PIL import Image

    img = Image.open(io.BytesIO(page.screenshot())).convert("RGB")
    a = np.asarray(img, dtype=np.int16)
    return a[:, : int(a.shape[1] * SCENE)]


def _drawn(a) -> float:
    import numpy as np

    bg = np.median(a.reshape(-1, 3), axis=0)
    return float(np.mean(np.abs(a - bg).sum(axis=2) > 60))


def _changed(a, b) -> float:
    import numpy as np

    return float(np.mean(np.abs(a - b).max(axis=2) > 30))


def _settle(page, t0: float, before=None, timeout: float = 120.0) -> tuple[float, float]:
    """(first, settled) seconds after t0: first picture (drawn, or changed from ``before``)
    and the moment two grabs 0.5 s apart agree."""
    first, last = None, None
    while time.perf_counter() - t0 < timeout:
        a = _grab(page)
        now = time.perf_counter() - t0
        if first is None:
            ok = _drawn(a) > 0.01 if before is None else _changed(before, a) > 0.001
            if ok:
                first = now
        elif last is not None and _changed(last, a) < 1e-4:
            return first, now
        last = a if first is not None else None
        time.sleep(0.5)
    return first or float("nan"), float("nan")


def _first_change(page, before, t0: float, timeout: float = 30.0) -> float:
    """Seconds after t0 until a grab differs from ``before`` (grabbing without pause:
    the resolution is one screenshot, ~0.1–0.3 s in software WebGL)."""
    while time.perf_counter() - t0 < timeout:
        if _changed(before, _grab(page)) > 0.001:
            return time.perf_counter() - t0
    return float("nan")


def _latency(page, setter, values) -> float:
    """Median seconds from ``setter(value)`` to the first changed picture."""
    out = []
    for value in values:
        time.sleep(1.0)  # the last change has settled
        before = _grab(page)
        t0 = time.perf_counter()
        setter(value)
        out.append(_first_change(page, before, t0))
    return statistics.median(out)


def worker(task: str, name: str | None, free: bool, solution: bool = True) -> dict:
    t0 = time.perf_counter()
    from playwright.sync_api import sync_playwright

    from orientviz.viewer.app import ViewerApp, resolve_content

    opts = {"free": True} if free else None
    try:  # as `orientviz view` opens it: a large imported model while it is being solved
        content = resolve_content(name or "radar", opts, background=True)
    except TypeError:  # a tree from before the background solve
        content = resolve_content(name or "radar", opts)
    try:  # as `orientviz view` starts it: a background solve waits for the first browser
        from orientviz.viewer.background import FIRST_BROWSER_WAIT

        wait = {"first_browser_wait": FIRST_BROWSER_WAIT}
    except ImportError:  # a tree from before that wait
        wait = {}
    app = ViewerApp(content, host="127.0.0.1", port=0, verbose=False, **wait)
    ready, cpu = time.perf_counter() - t0, time.process_time()
    out = {"process_s": ready, "process_cpu_s": cpu}
    profile = tempfile.mkdtemp(prefix="orientviz-bench-browser-")
    try:
        with sync_playwright() as p:
            ctx = p.chromium.launch_persistent_context(
                profile, executable_path="/usr/bin/chromium", headless=True, args=FLAGS,
                viewport={"width": WINDOW[0], "height": WINDOW[1]},
            )  # fmt: skip
            page = ctx.new_page()
            t1 = time.perf_counter()
            page.goto(app.url)
            page.add_style_tag(content=".mantine-Notifications-root {display: none !important}")
            first, settled = _settle(page, t1)
            out.update(first_s=first, settled_s=settled, total_s=ready + settled)
            job = getattr(app, "background", None)
            if job is not None and solution:  # the solution replaces the start values
                job.wait(600)
                out["solved_s"] = ready + _settle(page, t1)[1]
                out["solved_cpu_s"] = time.process_time()
            if task == "slide":
                h = app.panel.handles["omega"]
                times = []
                for value in (1.0, 0.0):
                    before = _grab(page)
                    t2 = time.perf_counter()
                    h.value = value
                    times.append(_settle(page, t2, before)[1])
                out["slide_s"] = statistics.median(times)
            if task == "cap":
                rv = app.extra["radar"]
                times = []
                for value in (30.0, 10.0):
                    before = _grab(page)
                    t2 = time.perf_counter()
                    rv.h["extent"].value = value
                    times.append(_settle(page, t2, before)[1])
                out["cap_s"] = statistics.median(times)
                # the first changed picture, and the page's floor: one node shown/hidden
                out["cap_first_s"] = _latency(
                    page, lambda v: setattr(rv.h["extent"], "value", v), (30.0, 10.0) * 2
                )
                out["toggle_first_s"] = _latency(
                    page, lambda v: setattr(rv.h["circles"], "value", v), (True, False) * 2
                )
            ctx.close()
    finally:
        app.stop()
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("task", choices=("open", "slide", "cap"))
    ap.add_argument("name", nargs="?", default=None)
    ap.add_argument("--free", action="store_true")
    ap.add_argument("--tree", action="append", default=[])
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument(
        "--no-solution", action="store_true",
        help="open: stop after the first settled picture (no wait for a background solve)",
    )  # fmt: skip
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.worker:
        print(json.dumps(worker(a.task, a.name, a.free, not a.no_solution)))
        return
    trees = a.tree or ["."]
    results: dict[str, list[dict]] = {t: [] for t in trees}
    for _ in range(a.repeat):
        for tree in trees:
            env = dict(os.environ, PYTHONPATH=os.path.join(os.path.abspath(tree), "src"))
            cmd = [sys.executable, os.path.abspath(__file__), a.task]
            cmd += ([a.name] if a.name else []) + (["--free"] if a.free else []) + ["--worker"]
            cmd += ["--no-solution"] if a.no_solution else []
            done = subprocess.run(
                cmd, env=env, capture_output=True, text=True, cwd=tempfile.gettempdir()
            )
            line = [s for s in done.stdout.splitlines() if s.startswith("{")]
            if not line:
                print(done.stderr[-2000:])
                raise SystemExit(f"the worker of {tree} failed")
            r = json.loads(line[-1])
            results[tree].append(r)
            print(tree, {k: round(v, 2) for k, v in r.items()}, flush=True)
    keys = ("process_s", "process_cpu_s", "first_s", "settled_s", "total_s", "solved_s",
            "solved_cpu_s", "slide_s", "cap_s", "cap_first_s", "toggle_first_s")  # fmt: skip
    med = {t: {k: statistics.median(r[k] for r in rs) for k in keys if k in rs[0]}
           for t, rs in results.items()}  # fmt: skip
    for t, m in med.items():
        print("median", t, {k: round(v, 2) for k, v in m.items()})
    if len(trees) == 2:
        A, B = med[trees[0]], med[trees[1]]
        print("ratio B/A", {k: round(B[k] / A[k], 3) for k in A if k in B and A[k]})


if __name__ == "__main__":
    main()
