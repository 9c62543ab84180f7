"""Sphinx configuration of the orientviz book, built offline with
`python -m sphinx -b html book book/_build/html` (tests/book/test_book.py builds it too).

For quick layout work without executing the notebooks (no outputs, no snapshots):
`python -m sphinx -b html -D nb_execution_mode=off book /tmp/book`.

The lesson notebooks live in ../notebooks; they are copied into lessons/ before each
build and executed by myst-nb, so the book always shows fresh results. Math is rendered
by a bundled MathJax (sphinx-mathjax-offline): no network is needed.
"""

from __future__ import annotations

import gc
import json
import os
import pathlib
import shutil
import sys

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(HERE / "_ext"))
# The kernels that execute the lessons inherit this environment: they import this
# checkout, whatever is installed, and draw with the inline backend (which emits PNGs),
# even when the build runs with MPLBACKEND=Agg (then figures would be text only).
os.environ["PYTHONPATH"] = os.pathsep.join(
    [str(ROOT / "src")] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
)
os.environ["MPLBACKEND"] = "module://matplotlib_inline.backend_inline"

import orientviz  # noqa: E402
from orientviz.io.jsonio import import_jsonschema  # noqa: E402

# myst-nb imports nbformat, which imports jsonschema: imported here first, without its optional
# format checkers' packages (one builds a grammar at import; no notebook schema has "format")
import_jsonschema()

project = "orientviz"
author = "the orientviz developers"
copyright = "2026, the orientviz developers (BSD-3-Clause)"
version = release = orientviz.__version__

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "numpydoc",
    "numpydoc_once",  # _ext/: numpydoc's template compiled once per build
    "sphinx.ext.viewcode",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",
    "orientviz_book",  # _ext/: static widget snapshots, failing cells named
]
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "**.ipynb_checkpoints", "jupyter_execute"]

# Execute every lesson during the build; a failing cell fails the build, and the message
# names the notebook, the cell and its first line (_ext/orientviz_book.py).
nb_execution_mode = "force"
nb_execution_timeout = 300
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True
# ipykernel ≥ 7.4 warns once per kernel ("[IPKernelApp] WARNING | Kernel is running over
# TCP without encryption ...") unless the kernel manager provisions CurveZMQ keys. The
# lessons' kernels get keys when their kernelspec declares support ("auto"; the standard
# python3 spec of ipykernel does), so the build log stays free of that line. The kernels
# still listen on 127.0.0.1 only. (The IPC transport, the other remedy, made myst-nb's
# kernel start time out on this machine.)
import zmq  # noqa: E402
from jupyter_client.manager import KernelManager  # noqa: E402

if zmq.has("curve"):  # libzmq built with libsodium (pyzmq's wheels are)
    KernelManager.transport_encryption.default_value = "auto"
# Widgets need a kernel; the static book shows a snapshot of each widget instead (the
# figures and text its Output widgets held after execution, _ext/orientviz_book.py).
# Leaving out the widget manager keeps every page free of CDN scripts (it works offline).
nb_ipywidgets_js: dict = {}

numpydoc_show_class_members = False  # autosummary lists the members already
numpydoc_class_members_toctree = False
autodoc_member_order = "bysource"
# the numpydoc Parameters give the types; expanded ArrayLike unions are unreadable
autodoc_typehints = "none"
# the package writes no PEP 484 type comments: autodoc need not parse each function's source
# for them (the pages are the same: 469 of 469 compared)
autodoc_use_type_comments = False
autosummary_generate = True
templates_path = ["_templates"]  # module pages document every member in full (numpydoc)

html_theme = "pydata_sphinx_theme"
html_title = "orientviz"
html_static_path = ["_static"]
# navigation_depth reaches the API's module pages (api → orientviz → package → module), so
# every page is in its own sidebar, and the theme can reuse one rendered sidebar for the
# pages of a section (at depth 2 it rendered the toctree anew for each of ~170 module pages)
html_theme_options = {
    "navigation_depth": 4,
    "show_toc_level": 2,
    "header_links_before_dropdown": 5,
    "navbar_align": "left",
}
# no external fonts, analytics or CDN assets: the book must work offline
html_theme_options["icon_links"] = []


#: With ORIENTVIZ_FIGURE_AUDIT=<file>, every lesson copy starts with a removed cell that
#: records the text sizes of each figure it shows (orientviz.plot.style.audit_figures);
#: tests/book/test_book.py reads the file to check that figures are readable in the column.
AUDIT = os.environ.get("ORIENTVIZ_FIGURE_AUDIT", "")


def _audit_cell(name: str) -> dict:
    src = f"from orientviz.plot.style import audit_figures\n_ = audit_figures({AUDIT!r}, {name!r})"
    return {
        "cell_type": "code",
        "execution_count": None,
        "id": "orientviz-figure-audit",
        "metadata": {"tags": ["remove-cell"]},
        "outputs": [],
        "source": src,
    }


def _copy_lessons(app) -> None:
    """Copy ../notebooks/*.ipynb into lessons/ so Sphinx can read them (srcdir only)."""
    target = HERE / "lessons"
    target.mkdir(exist_ok=True)
    wanted = {p.name for p in (ROOT / "notebooks").glob("*.ipynb")}
    for old in target.glob("*.ipynb"):
        if old.name not in wanted:
            old.unlink()
    for nb in sorted((ROOT / "notebooks").glob("*.ipynb")):
        if AUDIT:
            data = json.loads(nb.read_text(encoding="utf-8"))
            data["cells"].insert(0, _audit_cell(nb.stem))
            (target / nb.name).write_text(json.dumps(data, ensure_ascii=False), encoding="utf-8")
        else:
            shutil.copy2(nb, target / nb.name)


def _clear_generated(app) -> None:
    """Remove the API pages autosummary wrote in an earlier build (before it writes them
    again): a module that was moved or deleted since would otherwise keep a stale page that
    is in no toctree (a warning the book's test counts)."""
    for old in (HERE / "api" / "generated").glob("*.rst"):
        old.unlink()


def _collect_less(app) -> None:
    """Let the cyclic garbage collector run less often in the build's process.

    The build holds a few hundred thousand long-lived objects (the loaded extensions, the
    environment, every page's doctree); with the default thresholds (700, 10, 10) each of
    the frequent young-generation collections and the full ones walk them again (about a
    fifth of the build's own CPU). The objects that exist once the builder starts are frozen
    (never collected: they live to the end of the build anyway), and a collection of the
    youngest generation waits for 10 000 new objects instead of 700. The pages are the same;
    the kernels that execute the lessons are other processes and keep Python's defaults.
    """
    gc.freeze()
    gc.set_threshold(10_000, 20, 20)


def setup(app):
    app.connect("builder-inited", _collect_less, priority=50)  # before the stubs are written
    app.connect("builder-inited", _clear_generated, priority=100)  # before autosummary (500)
    app.connect("builder-inited", _copy_lessons)
