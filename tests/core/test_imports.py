"""The core imports neither matplotlib, ipywidgets nor viser (and stays fast)."""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[2] / "src" / "orientviz"

CORE = [
    "orientviz",
    "orientviz.units",
    "orientviz.rotation",
    "orientviz.camera",
    "orientviz.block",
    "orientviz.adjust",
    "orientviz.orientation",
    "orientviz.bundle",
    "orientviz.stereo_models",
    "orientviz.polynomial",
    "orientviz.simulate",
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
    assert loaded == ["orientviz", "orientviz.errors", "orientviz.version"]


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
    assert set(ov.__all__) == set(ov._FACE) | {
        "view",
        "AdjustmentError",
        "InputError",
        "NotDeterminableError",
        "OrientvizError",
        "__version__",
    }
    assert 20 <= len(ov.__all__) <= 36
    for name in ov.__all__:
        obj = getattr(ov, name)
        if name == "__version__":
            assert isinstance(obj, str)
            continue
        if name in ("TIE", "CONTROL", "CHECK"):  # the point roles: plain ints 0, 1, 2
            assert obj == ("TIE", "CONTROL", "CHECK").index(name)
            continue
        assert (obj.__doc__ or "").strip(), f"orientviz.{name} has no docstring"
        assert obj.__module__.startswith("orientviz"), f"orientviz.{name} is not orientviz's own"
    assert set(ov.__all__) <= set(dir(ov))


def test_unknown_face_name_is_an_attribute_error():
    import orientviz as ov

    with pytest.raises(AttributeError, match="no_such_name"):
        ov.no_such_name  # noqa: B018


#: What each layer may import from orientviz (dependencies point down): the engine knows
#: nothing of blocks, bundles or model methods; the block's data model knows no solver.
_SOLVERS = {
    "approximate",
    "bundle",
    "stereo_models",
    "polynomial",
    "simulate",
    "orientation",
    "radar",
}
_BASE = {"errors", "units", "rotation", "camera", "lens", "adjust", "block", "plausibility"}
LAYERS = {
    "adjust": {"errors", "units"},
    "block": {"errors", "units", "rotation", "camera", "adjust"},
    # io reads and writes files, below the reports: the problem kinds build their
    # Solution (io/solution.py) and know nothing of report/, plot/ or the GUIs
    "io": _BASE | _SOLVERS | {"report"},
    "report": _BASE | _SOLVERS | {"io", "plot", "version"},
}
#: Imports that are allowed only inside functions (run time, not import time).
LAZY_ONLY = {"io": {"report"}, "report": {"plot"}}
#: The only io modules that may call report/ (at run time): the two commands that write
#: a report or result tables on request (``orientviz solve --report``, ``orientviz export``).
IO_CALLS_REPORT = {"solve.py", "export.py"}


def _orientviz_imports(path: Path) -> list[tuple[str, bool]]:
    """Top-level orientviz subpackages/modules imported by a file, and whether at module level."""
    tree = ast.parse(path.read_text())
    pkg = path.relative_to(SRC).with_suffix("").parts[:-1]
    out = []
    top = {id(n) for n in tree.body}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = list(pkg[: len(pkg) - node.level + 1])
                parts = base + (node.module.split(".") if node.module else [])
                if not parts:  # from . import x at the package root
                    parts = [node.names[0].name]
            elif node.module and node.module.startswith("orientviz."):
                parts = node.module.split(".")[1:]
            else:
                continue
            out.append((parts[0], id(node) in top))
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("orientviz."):
                    out.append((a.name.split(".")[1], id(node) in top))
    return out


def test_dependencies_point_down():
    bad = []
    for layer, allowed in LAYERS.items():
        for path in sorted((SRC / layer).rglob("*.py")):
            for target, at_top in _orientviz_imports(path):
                if target == layer:
                    continue
                lazy = LAZY_ONLY.get(layer, set())
                if target not in allowed or (at_top and target in lazy):
                    bad.append(f"{path.relative_to(SRC)} imports orientviz.{target}")
    assert not bad, "imports against the direction of the layers:\n" + "\n".join(bad)


def test_io_does_not_import_the_reports():
    """No io↔report cycle: report → io only; io's two commands call the writers at run time."""
    bad = []
    for path in sorted((SRC / "io").rglob("*.py")):
        rel = path.relative_to(SRC / "io")
        for target, _ in _orientviz_imports(path):
            if target == "report" and str(rel) not in IO_CALLS_REPORT:
                bad.append(f"io/{rel} imports orientviz.report")
    assert not bad, "\n".join(bad)


def test_dependency_check_sees_an_upward_import(tmp_path, monkeypatch):
    # the checker itself must catch an upward import (a test that cannot fail is no test)
    fake = tmp_path / "adjust"
    fake.mkdir()
    (fake / "bad.py").write_text("from ..bundle import bundle_adjust\n")
    monkeypatch.setattr(sys.modules[__name__], "SRC", tmp_path)
    try:
        test_dependencies_point_down()
    except AssertionError as exc:
        assert "adjust/bad.py imports orientviz.bundle" in str(exc)
    else:
        raise AssertionError("the dependency check missed an upward import")
