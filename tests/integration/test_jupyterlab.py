"""A lesson, for real: JupyterLab on 127.0.0.1, the notebook run in headless Chromium,
a slider moved with the keyboard, and the figure seen to change.

The server runs in a temporary root holding a copy of lesson 02, with its own config,
data, runtime, settings and workspace directories (nothing of the user's Jupyter setup is
read or written). JupyterLab is asked to expose its application object
(``--LabApp.expose_app_in_browser``) so that the test can wait on the kernel's state and
run "Run All Cells" as a command instead of hunting for menu labels.
"""

from __future__ import annotations

import json
import os
import pathlib
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request

import pytest

from conftest import free_port

ROOT = pathlib.Path(__file__).parents[2]
LESSON = "02_rotations_and_collinearity.ipynb"
OVERALL_S = 180.0  # generous: a cold start on a busy 2-core machine
STEP_MS = 120_000

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


@pytest.mark.browser
@pytest.mark.slow
def test_lesson_runs_in_jupyterlab_and_slider_redraws(browser_page, tmp_path):
    pytest.importorskip("jupyterlab", reason="JupyterLab is not installed (pip install .[all])")
    pytest.importorskip(
        "jupyterlab_widgets", reason="the ipywidgets JupyterLab extension is missing"
    )
    pytest.importorskip("ipykernel", reason="ipykernel is not installed")
    deadline = time.monotonic() + OVERALL_S
    root = tmp_path / "root"
    root.mkdir()
    (root / LESSON).write_bytes((ROOT / "notebooks" / LESSON).read_bytes())
    port, token = free_port(), "orientviz-test-token"
    log = tmp_path / "jupyterlab.log"
    lab = _start_lab(root, port, token, log)
    page = browser_page
    try:
        _wait_http(f"http://127.0.0.1:{port}/api/status?token={token}", lab, deadline, log)
        page.set_default_timeout(STEP_MS)
        page.goto(f"http://127.0.0.1:{port}/lab/tree/{LESSON}?token={token}")
        page.wait_for_function(_NOTEBOOK, timeout=_remaining_ms(deadline))
        page.wait_for_function(_KERNEL_IDLE, timeout=_remaining_ms(deadline), polling=250)
        page.evaluate("() => window.jupyterapp.commands.execute('notebook:run-all-cells')")
        page.wait_for_function(_ALL_RUN, timeout=_remaining_ms(deadline), polling=250)
        assert page.evaluate(_ERRORS) == [], "the lesson raised in JupyterLab"

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
        _stop_lab(lab)
