"""Photograph the live viewer of each lesson for the offline book.

    python tools/make_lesson_snapshots.py            # every lesson that calls show_live
    python tools/make_lesson_snapshots.py 05 14      # lessons whose names start so

A lesson shows the viewer with ``orientviz.viewer.live.show_live(..., snapshot=NAME)``: an
IFrame of a viser server running in the lesson's kernel, on the state the lesson computed.
The book has no kernel; it shows ``book/_static/lesson_viewer/NAME.png`` instead
(``book/_ext/orientviz_book.py``). This tool executes the lesson (the teacher's version,
with the solutions) in a kernel it keeps alive, opens every viewer the lesson started in
headless Chromium (playwright with /usr/bin/chromium and the test suite's flags, software
WebGL), and saves the screenshot as a palette PNG (at most 400 KB, checked; a blank
picture stops the tool). So the picture is the scene of the lesson itself, not a demo.
"""

from __future__ import annotations

import argparse
import io
import os
import pathlib
import re
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import make_readme_figures as mrf  # noqa: E402  (the Chromium settings and the PNG writer)

ROOT = mrf.ROOT
OUT = ROOT / "book" / "_static" / "lesson_viewer"
KEY = "orientviz_viewer_snapshot"  # orientviz.viewer.live.SNAPSHOT_KEY
VIEWPORT = (1280, 860)
_SRC = re.compile(r'src="(http://127\.0\.0\.1:\d+)"')


def lessons(prefixes: list[str]) -> list[pathlib.Path]:
    """The lessons that call ``show_live`` (those whose names start with a prefix)."""
    found = []
    for nb in sorted((ROOT / "notebooks").glob("*.ipynb")):
        if prefixes and not any(nb.name.startswith(p) for p in prefixes):
            continue
        if "show_live(" in nb.read_text(encoding="utf-8"):
            found.append(nb)
    return found


def viewers(nb: object) -> list[tuple[str, str]]:
    """(snapshot name, URL) of every live viewer among the executed notebook's outputs."""
    out = []
    for cell in nb.cells:  # type: ignore[attr-defined]
        for o in cell.get("outputs", []):
            name = (o.get("metadata") or {}).get(KEY)
            if name:
                m = _SRC.search(str(o.get("data", {}).get("text/html", "")))
                if m is None:
                    raise SystemExit(f"viewer output {name!r} without a URL")
                out.append((str(name), m.group(1)))
    return out


def photograph(url: str, path: pathlib.Path, settle_s: float = 8.0) -> None:
    """Open ``url`` in headless Chromium, let the scene arrive, save the screenshot."""
    from PIL import Image
    from playwright.sync_api import sync_playwright

    chromium, flags = mrf._chromium_settings()
    profile = tempfile.mkdtemp(prefix="orientviz-lesson-chromium-")
    with sync_playwright() as p:
        context = p.chromium.launch_persistent_context(
            profile, executable_path=chromium, headless=True, args=flags,
            viewport={"width": VIEWPORT[0], "height": VIEWPORT[1]},
        )  # fmt: skip
        try:
            page = context.new_page()
            page.goto(url)
            page.wait_for_selector("canvas", timeout=120_000)
            # the "software WebGL" notice is about this headless machine, not the viewer
            page.add_style_tag(content=".mantine-Notifications-root {display: none}")
            time.sleep(settle_s)
            png = page.screenshot(timeout=180_000)
        finally:
            context.close()
    image = Image.open(io.BytesIO(png))
    if np.asarray(image.convert("RGB"), dtype=float).std() < 10:
        raise SystemExit(f"the screenshot of {url} ({path.name}) is blank")
    mrf._save_png(image, path)


def snapshot_lesson(path: pathlib.Path) -> list[pathlib.Path]:
    """Execute lesson ``path`` and photograph each of its live viewers."""
    import nbformat
    from nbclient import NotebookClient

    sys.path.insert(0, str(ROOT / "book" / "_ext"))
    from orientviz_book import patch_shell_polling

    patch_shell_polling()  # nbclient can lose the wake-up of a widget cell (see the book's ext)
    nb = nbformat.read(path, as_version=4)
    client = NotebookClient(nb, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(path.parent)}})  # fmt: skip
    written = []
    with client.setup_kernel():
        t0 = time.monotonic()
        for i, cell in enumerate(nb.cells):
            client.execute_cell(cell, i)
        print(f"{path.name}: executed in {time.monotonic() - t0:.0f} s", flush=True)
        for name, url in viewers(nb):
            target = OUT / f"{name}.png"
            photograph(url, target)
            written.append(target)
    return written


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("lessons", nargs="*", help="name prefixes, e.g. 05 14 (default: all)")
    args = p.parse_args(argv)
    os.environ["PYTHONPATH"] = os.pathsep.join(
        [str(ROOT / "src")] + [q for q in os.environ.get("PYTHONPATH", "").split(os.pathsep) if q]
    )
    os.environ["MPLBACKEND"] = "module://matplotlib_inline.backend_inline"
    OUT.mkdir(parents=True, exist_ok=True)
    todo = lessons(args.lessons)
    if not todo:
        raise SystemExit("no lesson with a live viewer matches")
    for nb in todo:
        snapshot_lesson(nb)


if __name__ == "__main__":
    main()
