"""The core imports neither matplotlib, ipywidgets nor viser (and stays fast)."""

import subprocess
import sys

CORE = [
    "orientviz",
    "orientviz.units",
    "orientviz.rotation",
    "orientviz.camera",
    "orientviz.model",
    "orientviz.adjust",
    "orientviz.orientation",
    "orientviz.block",
    "orientviz.radar",
    "orientviz.io",
    "orientviz.cli",
    "orientviz.exercises",
]


def test_core_has_no_gui_imports():
    code = (
        "import importlib, pkgutil, sys\n"
        f"for m in {CORE!r}:\n"
        "    importlib.import_module(m)\n"
        "    pkg = sys.modules[m]\n"
        "    for info in pkgutil.iter_modules(getattr(pkg, '__path__', [])):\n"
        "        importlib.import_module(m + '.' + info.name)\n"
        "bad = [k for k in ('matplotlib', 'ipywidgets', 'viser') if k in sys.modules]\n"
        "print(','.join(bad))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "", f"core modules imported {out.stdout.strip()}"
