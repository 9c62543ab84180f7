"""Shared fixtures: a headless Chromium page for the real-browser tests; Hypothesis profiles;
the lesson notebooks executed in this session."""

from __future__ import annotations

import os
import shutil
import socket
import tempfile

import pytest

try:  # property-based tests explore new inputs locally; CI replays a fixed sequence, so
    # that a landing run cannot turn red on an input nobody has seen (run the suite
    # locally to find new ones; a failing example is then reproduced by its printout)
    from hypothesis import settings as _hyp_settings

    _hyp_settings.register_profile("ci", derandomize=True, database=None)
    if os.environ.get("CI"):
        _hyp_settings.load_profile("ci")
except ImportError:  # hypothesis is a test dependency; tests that need it import it
    pass

CHROMIUM = os.environ.get("ORIENTVIZ_CHROMIUM", "/usr/bin/chromium")
CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
]


def free_port() -> int:
    """A TCP port on 127.0.0.1 that is free right now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def browser_page():
    """A fresh headless Chromium page (playwright), skipped with a reason if unavailable."""
    if not os.path.exists(CHROMIUM):
        pytest.skip(f"no Chromium at {CHROMIUM} (apt-get install -y chromium chromium-driver)")
    sync_api = pytest.importorskip("playwright.sync_api")
    profile = tempfile.mkdtemp(prefix="orientviz-chromium-")
    with sync_api.sync_playwright() as p:
        context = p.chromium.launch_persistent_context(
            profile,
            executable_path=CHROMIUM,
            headless=True,
            args=CHROMIUM_FLAGS,
            viewport={"width": 1280, "height": 800},
        )
        try:
            page = context.new_page()
            yield page
        finally:
            context.close()
            shutil.rmtree(profile, ignore_errors=True)


@pytest.fixture(scope="session")
def executed_lessons() -> dict[str, dict]:
    """Lesson notebooks executed in this session: file name → ``{"source": the notebook's
    text when it was executed, "notebook": the executed notebook (nbformat JSON)}``.

    The book build (tests/book/test_book.py) executes every lesson (myst-nb, an error in a
    cell fails the build) and records them here, so that tests/notebooks/test_notebooks.py
    checks those executions instead of running each lesson a second time; run alone, the
    notebook tests execute the lessons themselves.
    """
    return {}
