"""Lessons, for real: JupyterLab on 127.0.0.1, each notebook run in headless Chromium.

Lesson 02: a slider moved with the keyboard, and the figure seen to change. Lesson 05: the
live viewer (a viser server in the lesson's kernel, an IFrame of it in the output) seen
drawing its scene in the notebook.

One JupyterLab server serves this module: a temporary root holding copies of the two
lessons, with its own config, data, runtime, settings and workspace directories (nothing
of the user's Jupyter setup is read or written). Each test opens its lesson in a fresh
browser context (no cookies, storage or cache of the other test), runs it in a kernel of
its own and shuts that kernel down at its end. JupyterLab is asked to expose its
application object (``--LabApp.expose_app_in_browser``) so that the tests can wait on the
kernel's state and run "Run All Cells" as a command instead of hunting for menu labels.
"""

from __future__ import annotations

import io
import json
import os
import pathlib
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request

import numpy as np
import pytest

from conftest import free_port

ROOT = pathlib.Path(__file__).parents[2]
LESSON = "02_rotations_and_collinearity.ipynb"
LIVE_LESSON = "05_relative_orientation.ipynb"  # its last section shows the live viewer
START_S = 120.0  # the server's start: generous, a cold start on a busy 2-core machine
OVERALL_S = 180.0  # lesson 02 opened, run and its slider moved
LIVE_OVERALL_S = 300.0  # lesson 05 runs ~10-30 s, then its viewer draws
STEP_MS = 120_000
TOKEN = "orientviz-test-token"

# JS helpers; ``window.jupyterapp`` exists because of --LabApp.expose_app_in_browser
_NOTEBOOK = "() => window.jupyterapp && window.jupyterapp.shell.currentWidget"
_KERNEL_IDLE = """() => {
  const w = window.jupyterapp && window.jupyterapp.shell.currentWidget;
  const k = w && w.sessionContext && w.sessionContext.session
            && w.sessionContext.session.kernel;
  return !!(k && k.status === 'idle' && w.content && w.content.widgets.length > 0);
}"""
_ALL_RUN = """() => {
  const w = window.jupyterapp.shell.currentWidget;
  const k = w.sessionContext.session.kernel;
  const code = w.content.widgets.filter(c => c.model.type === 'code');
  const failed = code.some(c => c.model.outputs.toJSON().some(o => o.output_type === 'error'));
  return k.status === 'idle' && code.length > 0
         && (failed || code.every(c => c.model.executionCount !== null));
}"""  # true when all cells ran, or when one stopped the run with an error
_ERRORS = """() => {
  const w = window.jupyterapp.shell.currentWidget;
  const out = [];
  w.content.widgets.forEach((c, i) => {
    if (c.model.type !== 'code') return;
    for (const o of c.model.outputs.toJSON())
      if (o.output_type === 'error') out.push(`cell ${i}: ${o.ename}: ${o.evalue}`);
  });
  return out;
}"""


def _settings(directory: pathlib.Path) -> None:
    """User settings: render every cell (no windowing), no news or update pop-ups."""
    notebook = directory / "@jupyterlab" / "notebook-extension"
    notebook.mkdir(parents=True)
    (notebook / "tracker.jupyterlab-settings").write_text(json.dumps({"windowingMode": "none"}))
    apputils = directory / "@jupyterlab" / "apputils-extension"
    apputils.mkdir(parents=True)
    (apputils / "notification.jupyterlab-settings").write_text(
        json.dumps({"fetchNews": "false", "checkForUpdates": False})
    )


def _start_lab(root: pathlib.Path, port: int, token: str, log: pathlib.Path):
    state = root.parent / "jupyter-state"
    _settings(state / "settings")
    env = dict(
        os.environ,
        MPLBACKEND="module://matplotlib_inline.backend_inline",
        JUPYTER_CONFIG_DIR=str(state / "config"),
        JUPYTER_DATA_DIR=str(state / "data"),
        JUPYTER_RUNTIME_DIR=str(state / "runtime"),
        JUPYTERLAB_SETTINGS_DIR=str(state / "settings"),
        JUPYTERLAB_WORKSPACES_DIR=str(state / "workspaces"),
        PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT / "src"), os.environ.get("PYTHONPATH")])),
    )
    cmd = [
        sys.executable, "-m", "jupyterlab", "--no-browser", "--ip=127.0.0.1", f"--port={port}",
        "--ServerApp.port_retries=0", f"--IdentityProvider.token={token}",
        f"--ServerApp.root_dir={root}", "--LabApp.expose_app_in_browser=True",
        "--LabApp.news_url=", "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate",
    ]  # fmt: skip
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        cmd.append("--allow-root")  # containers and CI run as root
    with open(log, "wb") as f:
        return subprocess.Popen(
            cmd, stdout=f, stderr=subprocess.STDOUT, env=env, cwd=root, start_new_session=True
        )


def _stop_lab(lab: subprocess.Popen) -> None:
    """SIGTERM the server's process group (server and kernels), then SIGKILL what is left."""
    try:
        os.killpg(lab.pid, signal.SIGTERM)
        lab.wait(timeout=20)
    except (ProcessLookupError, subprocess.TimeoutExpired):
        pass
    try:
        os.killpg(lab.pid, signal.SIGKILL)  # a kernel may outlive its server
    except ProcessLookupError:
        pass
    lab.wait(timeout=10)


def _wait_http(url: str, lab: subprocess.Popen, deadline: float, log: pathlib.Path) -> None:
    while time.monotonic() < deadline:
        if lab.poll() is not None:
            raise RuntimeError(f"JupyterLab exited ({lab.returncode}):\n{log.read_text()[-3000:]}")
        try:
            with urllib.request.urlopen(url, timeout=3) as r:
                if r.status == 200:
                    return
        except (OSError, urllib.error.URLError):
            time.sleep(0.3)
    raise TimeoutError(f"JupyterLab did not answer at {url}:\n{log.read_text()[-3000:]}")


def _remaining_ms(deadline: float) -> float:
    return max(1000.0, (deadline - time.monotonic()) * 1000.0)


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """One JupyterLab server for this module's tests: ``(url, token, process)``; its root
    holds copies of both lessons."""
    pytest.importorskip("jupyterlab", reason="JupyterLab is not installed (pip install .[all])")
    pytest.importorskip("ipykernel", reason="ipykernel is not installed")
    base = tmp_path_factory.mktemp("jupyterlab")
    root = base / "root"
    root.mkdir()
    for name in (LESSON, LIVE_LESSON):
        (root / name).write_bytes((ROOT / "notebooks" / name).read_bytes())
    port = free_port()
    log = base / "jupyterlab.log"
    server = _start_lab(root, port, TOKEN, log)
    url = f"http://127.0.0.1:{port}"
    try:
        _wait_http(f"{url}/api/status?token={TOKEN}", server, time.monotonic() + START_S, log)
        yield url, TOKEN, server
    finally:
        _stop_lab(server)


def _shutdown_kernels(url: str, token: str) -> None:
    """End every session and kernel of the server (the next test's lesson starts its own)."""
    for kind in ("sessions", "kernels"):
        with urllib.request.urlopen(f"{url}/api/{kind}?token={token}", timeout=10) as r:
            ids = [item["id"] for item in json.loads(r.read())]
        for id_ in ids:
            req = urllib.request.Request(f"{url}/api/{kind}/{id_}?token={token}", method="DELETE")
            with urllib.request.urlopen(req, timeout=30):
                pass


def _run_all(page, url: str, token: str, lesson: str, deadline: float) -> None:
    """Open ``lesson`` in JupyterLab, wait for its kernel, "Run All Cells", wait for the end;
    no cell may raise."""
    page.set_default_timeout(STEP_MS)
    # ?reset: a workspace of its own (JupyterLab would reopen the other test's notebook)
    page.goto(f"{url}/lab/tree/{lesson}?reset&token={token}")
    page.wait_for_function(_NOTEBOOK, timeout=_remaining_ms(deadline))
    page.wait_for_function(_KERNEL_IDLE, timeout=_remaining_ms(deadline), polling=250)
    page.evaluate("() => window.jupyterapp.commands.execute('notebook:run-all-cells')")
    page.wait_for_function(_ALL_RUN, timeout=_remaining_ms(deadline), polling=250)
    assert page.evaluate(_ERRORS) == [], f"{lesson} raised in JupyterLab"


@pytest.mark.browser
@pytest.mark.slow
def test_lesson_runs_in_jupyterlab_and_slider_redraws(lab, browser_page, tmp_path):
    pytest.importorskip(
        "jupyterlab_widgets", reason="the ipywidgets JupyterLab extension is missing"
    )
    url, token, _ = lab
    deadline = time.monotonic() + OVERALL_S
    page = browser_page
    try:
        _run_all(page, url, token, LESSON, deadline)

        # the rotation app: sliders for ω, φ, κ beside an Output widget with the figure
        app = page.locator(".widget-hbox", has=page.locator(".widget-hslider")).first
        app.scroll_into_view_if_needed(timeout=_remaining_ms(deadline))
        figure = app.locator(".widget-output img").first
        figure.wait_for(state="attached", timeout=_remaining_ms(deadline))
        before = figure.get_attribute("src")
        assert before and before.startswith("data:image/png"), "the app shows no figure"
        readout = app.locator(".widget-hslider .widget-readout").first
        value_before = readout.text_content()

        handle = app.locator(".widget-hslider .noUi-handle").first
        handle.focus()
        for _ in range(10):  # 10 steps of 0.5 gon on ω
            page.keyboard.press("ArrowRight")

        moved = time.monotonic()
        changed = False
        while time.monotonic() < deadline:
            src = app.locator(".widget-output img").evaluate_all(  # no waiting: poll
                "els => els.length ? els[0].src : null"
            )
            if src and src.startswith("data:image/png") and src != before:
                changed = True
                break
            time.sleep(0.2)
        value_after = readout.text_content()
        if not changed:
            page.screenshot(path=str(tmp_path / "jupyterlab.png"))
        assert value_after != value_before, f"the slider did not move ({value_before!r})"
        assert changed, (
            f"ω moved {value_before} → {value_after} but the figure did not change within "
            f"{time.monotonic() - moved:.0f} s (screenshot {tmp_path / 'jupyterlab.png'})"
        )
    finally:
        _shutdown_kernels(url, token)


@pytest.mark.browser
@pytest.mark.slow
def test_lesson_shows_the_live_viewer_in_jupyterlab(lab, browser_page, tmp_path):
    """Lesson 05's last section calls ``orientviz.viewer.live.show_live``: a viser server
    in the lesson's kernel on 127.0.0.1 and an IFrame of it in the output. The test finds
    that IFrame in the output area, waits for the viewer's WebGL canvas inside it and its
    panel ("Your passes", the five dials), and checks that the canvas shows a scene: many
    non-background pixels of several colours."""
    pytest.importorskip("viser", reason="viser is not installed (pip install .[viewer])")
    from PIL import Image

    url, token, _ = lab
    deadline = time.monotonic() + LIVE_OVERALL_S
    page = browser_page
    shot = tmp_path / "jupyterlab_viewer.png"
    try:
        _run_all(page, url, token, LIVE_LESSON, deadline)

        # the IFrame of the live viewer, inside a cell's output area
        frame_el = page.locator(".jp-OutputArea-output iframe").first
        frame_el.scroll_into_view_if_needed(timeout=_remaining_ms(deadline))
        src = frame_el.get_attribute("src") or ""
        assert src.startswith("http://127.0.0.1:"), f"the viewer is not served locally: {src!r}"
        viewer = page.frame_locator(".jp-OutputArea-output iframe").first
        canvas = viewer.locator("canvas").first
        canvas.wait_for(state="visible", timeout=_remaining_ms(deadline))
        viewer.get_by_text("Your passes").first.wait_for(timeout=_remaining_ms(deadline))
        viewer.get_by_text("Dials of the right projector").first.wait_for(
            timeout=_remaining_ms(deadline)
        )

        # the scene arrives over the websocket and is drawn (software WebGL): poll the pixels
        drawn, share, colours = False, 0.0, 0
        while time.monotonic() < deadline:
            rgb = np.asarray(Image.open(io.BytesIO(canvas.screenshot())).convert("RGB"), int)
            background = np.median(rgb.reshape(-1, 3), axis=0)
            differs = np.abs(rgb - background).sum(axis=2) > 60
            share = float(differs.mean())
            colours = len({tuple(c // 32) for c in rgb[differs][:: max(1, differs.sum() // 4000)]})
            if share > 0.01 and colours >= 4:
                drawn = True
                break
            time.sleep(1.0)
        page.screenshot(path=str(shot), full_page=False)
        assert drawn, (
            f"the viewer's canvas in the notebook stays blank: {share:.2%} of its pixels differ "
            f"from the background, {colours} colour groups (screenshot {shot})"
        )
    finally:
        _shutdown_kernels(url, token)
