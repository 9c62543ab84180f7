"""The core imports neither matplotlib, ipywidgets nor viser (and stays fast)."""

import subprocess
import sys

import pytest

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
    "orientviz.report",
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


def _run(code: str) -> str:
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return out.stdout.strip()


def test_import_orientviz_loads_only_the_face():
    # the face is lazy: no numpy, no scipy, no solver module until a name is used
    loaded = _run(
        "import sys\n"
        "import orientviz\n"
        "print(' '.join(sorted(k for k in sys.modules\n"
        "    if k.split('.')[0] in ('orientviz', 'numpy', 'scipy', 'matplotlib', 'viser', 'ipywidgets'))))\n"
    ).split()
    assert loaded == ["orientviz", "orientviz.errors"]


def test_face_names_load_no_gui_and_view_imports_the_viewer_only_when_called():
    loaded = _run(
        "import sys\n"
        "import orientviz as ov\n"
        "for name in ov.__all__:\n"
        "    getattr(ov, name)\n"
        "print(' '.join(k for k in ('matplotlib', 'ipywidgets', 'viser', 'orientviz.viewer')\n"
        "               if k in sys.modules))\n"
    )
    assert loaded == ""


def test_every_face_name_resolves_and_has_a_docstring():
    import orientviz as ov

    assert ov.__all__ == sorted(set(ov.__all__))
    assert 20 <= len(ov.__all__) <= 36
    for name in ov.__all__:
        obj = getattr(ov, name)
        if name == "__version__":
            assert isinstance(obj, str)
            continue
        assert (obj.__doc__ or "").strip(), f"orientviz.{name} has no docstring"
        assert obj.__module__.startswith("orientviz"), f"orientviz.{name} is not orientviz's own"
    assert set(ov.__all__) <= set(dir(ov))


def test_unknown_face_name_is_an_attribute_error():
    import orientviz as ov

    with pytest.raises(AttributeError, match="no_such_name"):
        ov.no_such_name  # noqa: B018
