"""The import graph: the core imports no GUI library, the front door stays lazy, the
packages import downwards only, no circle, no lazy import without a reason, and no
module reaches into another package's private modules.

The graph is read from the code (``ast``), every ``import`` statement of src/orientviz
including those inside functions (imports under ``if TYPE_CHECKING:`` are annotations,
not imports, and are left out).
"""

import ast
import functools
import subprocess
import sys
from collections import defaultdict, deque
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[2] / "src" / "orientviz"

CORE = [
    "orientviz",
    "orientviz.units",
    "orientviz.rotation",
    "orientviz.camera",
    "orientviz.block",
    "orientviz.approximate",
    "orientviz.design",
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
    assert loaded == ["orientviz", "orientviz.errors", "orientviz.faces", "orientviz.version"]


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


#: The packages (and top-level modules) of orientviz from the top down. A module may
#: import from its own package and from the rows below its own, never from its row or
#: above: dependencies point down, and no two packages import each other.
LAYERS: list[tuple[str, ...]] = [
    ("cli",),  # the `orientviz` command: dispatches to the command modules
    ("orientviz",),  # the front door (__init__.py): its names are loaded on first use
    ("viewer", "widgets", "datasets"),  # the GUIs; the scripts that write the shipped data
    ("report",),  # what a solve tells (text, HTML with figures, result tables)
    ("plot",),  # matplotlib figures
    ("reproduce",),  # the papers' tables beside orientviz's numbers
    ("io", "exercises", "design"),  # files; the lessons' checkers; planning a block
    ("approximate", "simulate", "polynomial"),  # start values; simulated blocks; polynomials
    ("stereo_models",),  # independent models
    ("bundle",),  # the bundle adjustment
    ("orientation", "radar", "plausibility"),  # single images and pairs, radar, checks
    ("block",),  # the block's data model
    ("adjust", "camera"),  # the engine; the frame camera
    ("rotation", "lens"),
    ("units", "errors", "version", "blas", "faces"),
]
#: Packages whose modules may import other packages' private modules (none).
PRIVATE_OK: set[str] = set()


def _module_name(path: Path, src: Path) -> str:
    parts = list(path.relative_to(src.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _walk_marked(tree: ast.AST):
    """The nodes of ``tree`` in :func:`ast.walk`'s order, each with two marks: inside a
    function or class body; under ``if TYPE_CHECKING:`` (annotations only, never run).
    One pass instead of a walk per mark and per scope."""
    scope = (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)
    todo = deque([(tree, False, False)])
    while todo:
        node, inside, checking = todo.popleft()
        below = inside or isinstance(node, scope)
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            body = {id(stmt) for stmt in node.body}
            todo.extend((c, below, checking or id(c) in body) for c in ast.iter_child_nodes(node))
        else:
            todo.extend((c, below, checking) for c in ast.iter_child_nodes(node))
        yield node, inside, checking


@functools.lru_cache(maxsize=4)
def import_graph(src: Path = SRC) -> list[tuple[str, str, int, bool, str]]:
    """Every import of orientviz by a module of ``src``: (importer, imported module,
    line, lazy, the line's text). ``lazy``: inside a function or class body."""
    modules = {_module_name(p, src): p for p in src.rglob("*.py")}
    edges = []
    for name, path in sorted(modules.items()):
        text = path.read_text(encoding="utf-8")
        lines = text.splitlines()
        tree = ast.parse(text)
        package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
        for node, inner, checking in _walk_marked(tree):
            if checking:
                continue
            targets = []
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package[: len(package) - node.level + 1]
                    base = ".".join(base + ([node.module] if node.module else []))
                elif node.module and node.module.split(".")[0] == src.name:
                    base = node.module
                else:
                    continue
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base
                           for a in node.names]  # fmt: skip
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names if a.name.split(".")[0] == src.name]
            for target in dict.fromkeys(targets):
                line = lines[node.lineno - 1]
                edges.append((name, target, node.lineno, inner, line))
    return edges


def _package(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else parts[0]


def _row(package: str) -> int:
    for i, row in enumerate(LAYERS):
        if package in row:
            return i
    raise KeyError(package)


def _path(module: str, src: Path) -> str:
    return "/".join(module.split(".")[1:]) or "__init__"


def test_every_package_has_a_row():
    packages = {_package(_module_name(p, SRC)) for p in SRC.rglob("*.py")}
    placed = {p for row in LAYERS for p in row}
    assert packages - placed == set(), "give these packages a row in LAYERS"
    assert placed - packages == set(), "LAYERS names packages that do not exist"


def test_dependencies_point_down():
    bad = []
    for a, b, line, _, _ in import_graph(SRC):
        pa, pb = _package(a), _package(b)
        if pa != pb and _row(pb) <= _row(pa):
            bad.append(f"{_path(a, SRC)}.py:{line} imports {b} (row {_row(pa)} -> row {_row(pb)})")
    assert not bad, "imports against the direction of the layers:\n" + "\n".join(bad)


def cycles(edges) -> list[set[str]]:
    """The circles of the module graph (strongly connected parts of more than one module)."""
    graph = defaultdict(set)
    for a, b, *_ in edges:
        if a != b:
            graph[a].add(b)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    out = []
    for root in sorted(graph):  # Tarjan, iterative
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    work.append((w, iter(sorted(graph[w]))))
                elif w in stack:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                part = set()
                while True:
                    w = stack.pop()
                    part.add(w)
                    if w == v:
                        break
                if len(part) > 1:
                    out.append(part)
    return out


def test_no_circle_between_modules():
    found = [sorted(c) for c in cycles(import_graph(SRC))]
    assert not found, "modules that import each other (directly or round a circle):\n" + "\n".join(
        map(str, found)
    )


def test_lazy_imports_say_why():
    """An import inside a function only where it keeps a first import fast or a GUI library
    out of the core, and then with a one-line reason as a comment on its line."""
    bare = [
        f"{_path(a, SRC)}.py:{line} {text.strip()}"
        for a, _, line, lazy, text in import_graph(SRC)
        if lazy and "#" not in text
    ]
    assert not bare, "lazy imports without a reason (import at the top instead):\n" + "\n".join(
        bare
    )


def test_no_module_imports_another_packages_private_modules():
    """A package's private modules (``_*.py``, at any depth) are imported only from inside
    that package (the packages of LAYERS)."""
    bad = []
    for a, b, line, _, _ in import_graph(SRC):
        parts = b.split(".")
        private = [i for i, p in enumerate(parts) if p.startswith("_") and p != "__init__"]
        if private and _package(a) != _package(b) and _package(a) not in PRIVATE_OK:
            bad.append(f"{_path(a, SRC)}.py:{line} imports {b}")
    assert not bad, "imports of another package's private modules:\n" + "\n".join(bad)


def test_tests_use_public_names_outside_their_package():
    """A test imports a private module only in its package's own folder (tests/<package>/)."""
    tests = SRC.parents[1] / "tests"
    bad = []
    for path in sorted(tests.rglob("*.py")):
        area = path.relative_to(tests).parts[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = []
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("orientviz"):
                names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names if a.name.startswith("orientviz")]
            for name in names:
                parts = name.split(".")
                if any(p.startswith("_") and not p.startswith("__") for p in parts) and (
                    len(parts) < 2 or parts[1] != area
                ):
                    bad.append(f"{path.relative_to(tests)}:{node.lineno} {name}")
    assert not bad, "tests reaching into other packages' private names:\n" + "\n".join(bad)


def test_the_checks_see_an_upward_import_a_circle_and_a_bare_lazy_import(tmp_path, monkeypatch):
    # the checker itself must catch what it forbids (a test that cannot fail is no test)
    src = tmp_path / "orientviz"
    (src / "adjust").mkdir(parents=True)
    (src / "bundle").mkdir()
    (src / "adjust" / "__init__.py").write_text("")
    (src / "adjust" / "bad.py").write_text("from ..bundle import bundle_adjust\n")
    (src / "bundle" / "__init__.py").write_text("from ._one import f\n")
    (src / "bundle" / "_one.py").write_text("def f():\n    from ._two import g\n")
    (src / "bundle" / "_two.py").write_text("from ._one import f\nfrom ..adjust._x import y\n")
    monkeypatch.setattr(sys.modules[__name__], "SRC", src)
    with pytest.raises(AssertionError, match=r"adjust/bad.py:1 imports orientviz.bundle "):
        test_dependencies_point_down()
    with pytest.raises(AssertionError, match=r"orientviz.bundle._one', 'orientviz.bundle._two"):
        test_no_circle_between_modules()
    with pytest.raises(AssertionError, match=r"bundle/_one.py:2 from ._two import g"):
        test_lazy_imports_say_why()
    with pytest.raises(AssertionError, match=r"bundle/_two.py:2 imports orientviz.adjust._x"):
        test_no_module_imports_another_packages_private_modules()
