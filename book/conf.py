"""Sphinx configuration of the orientviz book, built offline with
`python -m sphinx -b html book book/_build/html`.

The lesson notebooks live in ../notebooks; they are copied into lessons/ before each
build and executed by myst-nb, so the book always shows fresh results. Math is rendered
by a bundled MathJax (sphinx-mathjax-offline): no network is needed.
"""

from __future__ import annotations

import pathlib
import shutil
import sys

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT / "src"))

import orientviz  # noqa: E402

project = "orientviz"
author = "the orientviz developers"
copyright = "2026, the orientviz developers (BSD-3-Clause)"
version = release = orientviz.__version__

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.viewcode",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",
]
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "**.ipynb_checkpoints", "jupyter_execute"]

# Execute every lesson during the build; a failing cell fails the build and names it.
nb_execution_mode = "force"
nb_execution_timeout = 300
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True
# Widgets need a kernel; the static book shows the figures printed beside them instead.
# Leaving out the widget manager keeps every page free of CDN scripts (it works offline).
nb_ipywidgets_js: dict = {}

napoleon_numpy_docstring = True
napoleon_google_docstring = False
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autosummary_generate = True

html_theme = "pydata_sphinx_theme"
html_title = "orientviz — photogrammetric orientation, visible"
html_static_path = ["_static"]
html_theme_options = {"navigation_depth": 2, "show_toc_level": 2}
# no external fonts, analytics or CDN assets: the book must work offline
html_theme_options["icon_links"] = []


def _copy_lessons(app) -> None:
    """Copy ../notebooks/*.ipynb into lessons/ so Sphinx can read them (srcdir only)."""
    target = HERE / "lessons"
    target.mkdir(exist_ok=True)
    wanted = {p.name for p in (ROOT / "notebooks").glob("*.ipynb")}
    for old in target.glob("*.ipynb"):
        if old.name not in wanted:
            old.unlink()
    for nb in sorted((ROOT / "notebooks").glob("*.ipynb")):
        shutil.copy2(nb, target / nb.name)


def setup(app):
    app.connect("builder-inited", _copy_lessons)
