"""The student release (tools/make_student_release.py): no solution line survives, hidden
tests are gone, and the check after each blank may raise without stopping "Run All"."""

from __future__ import annotations

import json
import os
import pathlib

import pytest
from release_tool import release

BEGIN, END, MD_BEGIN, MD_END = release.BEGIN, release.END, release.MD_BEGIN, release.MD_END
HIDDEN_BEGIN, HIDDEN_END = release.HIDDEN_BEGIN, release.HIDDEN_END
HIDDEN_NOTE = release.HIDDEN_NOTE
main, strip_source, release_notebook = release.main, release.strip_source, release.release_notebook

ROOT = pathlib.Path(__file__).parents[2]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


def _source(cell):
    src = cell.get("source", "")
    return "".join(src) if isinstance(src, list) else src


def _solution_lines(text, begin, end):
    """Non-blank lines inside solution blocks that do not also occur outside them."""
    inside, body, outside = False, set(), set()
    for line in text.splitlines():
        s = line.strip()
        if s == begin:
            inside = True
        elif s == end:
            inside = False
        elif s:
            (body if inside else outside).add(s)
    return body - outside


def test_strip_source_keeps_indentation_and_context():
    src = f"def f(x):\n    '''doc'''\n    {BEGIN}\n    y = 2 * x\n    return y\n    {END}\n\nprint(f)\n"
    out, n = strip_source(src)
    assert n == 1
    assert out == "def f(x):\n    '''doc'''\n    raise NotImplementedError\n\nprint(f)\n"
    ns = {}
    exec(compile(out.replace("print(f)", ""), "<cell>", "exec"), ns)
    with pytest.raises(NotImplementedError):
        ns["f"](1)


def test_strip_source_markdown_and_errors():
    out, n = strip_source(f"Why?\n{MD_BEGIN}\nBecause.\n{MD_END}\n", markdown=True)
    assert n == 1 and "Because" not in out and "*(your answer)*" in out
    for bad in (f"{BEGIN}\nx\n", f"x\n{END}\n", f"{BEGIN}\n{BEGIN}\n{END}\n"):
        with pytest.raises(ValueError):
            strip_source(bad)


def test_hidden_tests_are_removed():
    src = f"check(f)\n{HIDDEN_BEGIN}\nassert f(2) == 4\n{HIDDEN_END}\nprint('done')\n"
    out, n = strip_source(src)
    assert n == 0 and out == "check(f)\nprint('done')\n"
    with pytest.raises(ValueError):
        strip_source(f"{HIDDEN_BEGIN}\nx\n")


def test_a_release_names_the_checks_it_needs_and_stops_on_another_orientviz():
    from orientviz.exercises import CheckFailed, release_check

    def code(s):
        return {"cell_type": "code", "source": s, "metadata": {}, "outputs": [],
                "execution_count": None}  # fmt: skip

    nb = {"cells": [code("import numpy as np"), code("def check_mine(f):\n    pass"),
                    code("from orientviz.simulate import check_errors\ncheck_errors(s, a)"),
                    code("ex.check_condition(misclosure)\ncheck_mine(g)")],
          "metadata": {}, "nbformat": 4, "nbformat_minor": 5}  # fmt: skip
    student, _ = release_notebook(nb, "05", "abc1234")
    first = student["cells"][0]["source"]
    assert first.startswith("import numpy as np") and len(student["cells"]) == 4
    assert "release_check('05', ['check_condition'], made_with='abc1234')" in first
    release_check("05", ["check_condition"], "abc1234")  # present: no error
    with pytest.raises(CheckFailed, match="check_six_point.*abc1234|abc1234.*check_six_point"):
        release_check("05", ["check_condition", "check_six_point"], "abc1234")


def test_a_cell_of_hidden_tests_only_says_so():
    def code(s):
        return {"cell_type": "code", "source": s, "metadata": {}, "outputs": [],
                "execution_count": None}  # fmt: skip

    hidden = f"{HIDDEN_BEGIN}\nassert f(2) == 4\n{HIDDEN_END}\n"
    nb = {"cells": [code("a = 1"), code(hidden), code(""), code("b = 2")], "metadata": {},
          "nbformat": 4, "nbformat_minor": 5}  # fmt: skip
    student, _ = release_notebook(nb)
    assert [c["source"] for c in student["cells"]] == ["a = 1", HIDDEN_NOTE, "", "b = 2"]


def test_the_check_after_a_blank_may_raise():
    def code(s, tags=()):
        return {"cell_type": "code", "source": s, "metadata": {"tags": list(tags)} if tags else {},
                "outputs": [], "execution_count": None}  # fmt: skip

    nb = {"cells": [code("import x"), code(f"def f():\n    {BEGIN}\n    return 1\n    {END}\n",
                    ["hide-cell"]), code(""), code("check(f)"), code("y = f()")],
          "metadata": {}, "nbformat": 4, "nbformat_minor": 5}  # fmt: skip
    student, n = release_notebook(nb)
    tags = [c["metadata"].get("tags", []) for c in student["cells"]]
    assert n == 1 and tags == [[], [], [], ["raises-exception"], []]


def test_release_unhides_and_clears():
    cell = {
        "cell_type": "code",
        "source": [f"{BEGIN}\n", "x = 1\n", f"{END}\n"],
        "metadata": {
            "tags": ["hide-cell"],
            "mystnb": {"code_prompt_show": "Show"},
            "jupyter": {"source_hidden": True},
        },
        "outputs": [{"output_type": "stream", "name": "stdout", "text": "1"}],
        "execution_count": 3,
    }
    student, n = release_notebook(
        {"cells": [cell], "metadata": {}, "nbformat": 4, "nbformat_minor": 5}
    )
    out = student["cells"][0]
    assert n == 1 and out["source"] == "raise NotImplementedError\n"
    assert out["metadata"] == {} and out["outputs"] == [] and out["execution_count"] is None
    assert cell["execution_count"] == 3  # the original is untouched


@pytest.mark.skipif(not NOTEBOOKS, reason="no notebooks")
def test_no_solution_line_survives_in_the_student_copies(tmp_path, capsys):
    assert main([str(ROOT / "notebooks"), str(tmp_path)]) == 0
    for path in NOTEBOOKS:
        original = json.loads(path.read_text(encoding="utf-8"))
        student = json.loads((tmp_path / path.name).read_text(encoding="utf-8"))
        assert len(student["cells"]) == len(original["cells"])
        for a, b in zip(original["cells"], student["cells"]):
            md = a["cell_type"] == "markdown"
            begin, end = (MD_BEGIN, MD_END) if md else (BEGIN, END)
            text, stripped = _source(a), _source(b)
            blank = "*(your answer)*" if md else "raise NotImplementedError"
            assert stripped.count(blank) >= text.count(begin), path.name
            assert begin not in stripped and end not in stripped, path.name
            kept = {line.strip() for line in stripped.splitlines()}
            leaked = _solution_lines(text, begin, end) & kept
            assert not leaked, f"{path.name}: solution lines survive: {sorted(leaked)[:3]}"


def test_main_usage_errors(tmp_path, capsys):
    assert main([]) == 2
    assert main([str(tmp_path / "missing.ipynb"), str(tmp_path / "out")]) == 1
    assert main([str(ROOT / "notebooks"), str(ROOT / "notebooks")]) == 1


#: Run in the shared kernel before each released lesson: an empty namespace, no figures,
#: matplotlib's settings as they were before the first lesson, the lesson's own folder.
RESET = """\
%reset -f
import os as _os, sys as _sys
import matplotlib as _mpl, matplotlib.pyplot as _plt
_plt.close("all")
_sys.__dict__.setdefault("_orientviz_rc", dict(_mpl.rcParams))
_mpl.rcParams.update(_sys._orientviz_rc)
_os.chdir({path!r})
del _os, _sys, _mpl, _plt
"""


@pytest.fixture(scope="module")
def lesson_kernel():
    """One kernel for all released lessons (a kernel start with its imports costs about
    as much CPU as a short lesson). Before each lesson :data:`RESET` empties it; each
    lesson as written also runs in a fresh kernel of its own in the book build
    (tests/book/test_book.py) or tests/notebooks/test_notebooks.py."""
    jupyter_client = pytest.importorskip("jupyter_client")
    km = jupyter_client.KernelManager(kernel_name="python3")
    km.start_kernel(env=dict(os.environ, MPLBACKEND="Agg"))
    try:
        yield km
    finally:
        km.shutdown_kernel(now=False)


def _execute(nb, km, path):
    nbclient = pytest.importorskip("nbclient")
    client = nbclient.NotebookClient(nb, km=km, timeout=300, kernel_name="python3",
                                     resources={"metadata": {"path": str(path)}})  # fmt: skip
    try:
        return client.execute()
    finally:
        if client.kc is not None:
            client.kc.stop_channels()


def _run_release(path, tmp_path, km):
    """Release one lesson into tmp_path and execute it as "Run All" does; return the notebook."""
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    from test_notebooks import _patch_shell_polling

    _patch_shell_polling()
    assert main([str(path), str(tmp_path)]) == 0
    nb = nbformat.read(tmp_path / path.name, as_version=4)
    reset = nbformat.v4.new_notebook(
        cells=[nbformat.v4.new_code_cell(RESET.format(path=str(tmp_path)))]
    )
    _execute(reset, km, tmp_path)
    try:
        _execute(nb, km, tmp_path)  # a cell not tagged raises-exception that raises stops here
    except nbclient.exceptions.CellExecutionError as exc:
        pytest.fail(f"{path.name}: the student release stops: {str(exc).splitlines()[-1]}")
    return nb


@pytest.mark.notebook
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_released_lesson_runs_to_the_end(path, tmp_path, lesson_kernel):
    """ "Run All" on the student release reaches the last cell; the only errors are the checks
    of the blanks, each saying "not written yet"."""
    nb = _run_release(path, tmp_path, lesson_kernel)
    errors, blanks = [], 0
    for i, cell in enumerate(nb.cells):
        if cell.cell_type != "code":
            continue
        assert cell.source.strip() == "" or cell.execution_count is not None, f"cell {i} not run"
        for out in cell.get("outputs", []):
            if out.get("output_type") == "error":
                if out.get("ename") == "NotWrittenError" and "not written yet" in out.get(
                    "evalue", ""
                ):
                    blanks += 1
                else:
                    errors.append(f"cell {i}: {out.get('ename')}: {out.get('evalue', '')[:200]}")
    assert not errors, f"{path.name}: errors other than 'not written yet':\n" + "\n".join(errors)
    assert blanks >= 4, f"{path.name}: only {blanks} checks answered 'not written yet'"
