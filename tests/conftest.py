"""Shared fixtures: a headless Chromium page for the real-browser tests; Hypothesis profiles;
the lesson notebooks executed in this session."""

from __future__ import annotations

import os
import socket

# BLAS on one thread in the tests and in every process they start (lesson kernels, the book
# build, the command line): the tests' matrices are small, and on a shared machine a second
# BLAS thread mostly spins waiting for a core (several times the CPU for the same result).
# Set before numpy loads; a value given in the environment is kept.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import compileall  # noqa: E402
import gc  # noqa: E402
import importlib.util  # noqa: E402
import sys  # noqa: E402

import pytest  # noqa: E402

# Bytecode of the package once, before the suite starts its ~50 Python processes (lesson
# kernels, the book's Sphinx, command-line and example runs): an editable install has none,
# and where PYTHONDONTWRITEBYTECODE is set every one of those processes would compile the
# ~280 modules it imports anew (~0.3 s CPU for a lesson kernel's imports). pip does the same
# when it installs a wheel; files already compiled are skipped by their time stamp.
_package = importlib.util.find_spec("orientviz")
if _package is not None and _package.submodule_search_locations:
    compileall.compile_dir(_package.submodule_search_locations[0], quiet=2)

from orientviz.io.jsonio import import_jsonschema  # noqa: E402

# jsonschema (nbformat, the notebook and problem-file tests use it) imported once without its
# optional format checkers' packages (rfc3987_syntax builds a grammar at import: ~1.3 s CPU);
# no schema validated here has a "format" keyword (orientviz's, nbformat's): nothing changes
import_jsonschema()

# pytest rewrites the asserts of every module of a distribution that ships a pytest plugin,
# so hypothesis's ~130 modules too; where PYTHONDONTWRITEBYTECODE is set nothing keeps the
# result and every run parsed and rewrote them anew (~0.6 s CPU). Their asserts are
# hypothesis's own checks, not the tests' (the test modules are rewritten as before).
for _hook in sys.meta_path:
    if isinstance(getattr(_hook, "_must_rewrite", None), set):
        _hook._must_rewrite.discard("hypothesis")
        getattr(_hook, "_marked_for_rewrite_cache", {}).clear()

try:  # property-based tests explore new inputs locally; CI replays a fixed sequence, so
    # that a landing run cannot turn red on an input nobody has seen (run the suite
    # locally to find new ones; a failing example is then reproduced by its printout)
    from hypothesis import settings as _hyp_settings

    _hyp_settings.register_profile("ci", derandomize=True, database=None)
    if os.environ.get("CI"):
        _hyp_settings.load_profile("ci")
except ImportError:  # hypothesis is a test dependency; tests that need it import it
    pass


def pytest_collection_finish(session):
    """Freeze what exists once the tests are collected (the imported modules, the test
    items and their parameters: they live to the end of the run), so that the cyclic
    garbage collector's full collections stop walking them again. Objects the tests make
    are collected as before; the thresholds stay Python's defaults."""
    gc.freeze()


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


@pytest.fixture(scope="module")
def _chromium():
    """One headless Chromium (playwright) per test module, skipped with a reason if unavailable;
    each test gets a fresh context of its own (:func:`browser_page`)."""
    if not os.path.exists(CHROMIUM):
        pytest.skip(f"no Chromium at {CHROMIUM} (apt-get install -y chromium chromium-driver)")
    sync_api = pytest.importorskip("playwright.sync_api")
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_FLAGS)
        try:
            yield browser
        finally:
            browser.close()


@pytest.fixture
def browser_page(_chromium):
    """A fresh headless Chromium page in a context of its own (no cookies, storage or cache
    shared with another test), closed afterwards."""
    context = _chromium.new_context(viewport={"width": 1280, "height": 800})
    try:
        yield context.new_page()
    finally:
        context.close()


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
