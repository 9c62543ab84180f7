"""Every lesson notebook executes top to bottom, and none is committed with outputs."""

from __future__ import annotations

import json
import pathlib
import sys

import pytest

ROOT = pathlib.Path(__file__).parents[2]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


def _patch_shell_polling() -> None:
    """Use the book's workaround for nbclient's lost shell wake-up (see book/_ext)."""
    sys.path.insert(0, str(ROOT / "book" / "_ext"))
    try:
        from orientviz_book import patch_shell_polling
    except ImportError:  # no Sphinx/docutils: run unpatched (a stall then ends at the timeout)
        return
    finally:
        sys.path.pop(0)
    patch_shell_polling()


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_has_no_outputs(path):
    nb = json.loads(path.read_text(encoding="utf-8"))
    for i, cell in enumerate(nb["cells"]):
        if cell["cell_type"] == "code":
            assert not cell.get("outputs"), f"{path.name}: cell {i} has committed outputs"
            assert cell.get("execution_count") is None, (
                f"{path.name}: cell {i} has an execution count"
            )


def _check_executed(name: str, nb: dict) -> None:
    """Every code cell of an executed notebook ran, and none raised (but those tagged
    ``raises-exception``, which nbclient and myst-nb let raise too)."""
    for i, cell in enumerate(nb["cells"]):
        if cell["cell_type"] != "code" or not cell["source"]:
            continue
        assert cell.get("execution_count") is not None, f"{name}: cell {i} did not run"
        errors = [o for o in cell.get("outputs", []) if o.get("output_type") == "error"]
        if "raises-exception" in cell.get("metadata", {}).get("tags", []):
            continue
        assert not errors, f"{name}: cell {i} raised {errors[0].get('ename')}"


@pytest.mark.notebook
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_runs(path, tmp_path, monkeypatch, executed_lessons):
    done = executed_lessons.get(path.name)
    if done is not None and done["source"] == path.read_text(encoding="utf-8"):
        # executed in this session by the book build (myst-nb): check that execution
        _check_executed(path.name, done["notebook"])
        return
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    _patch_shell_polling()
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(
        nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    )
    try:
        client.execute()
    except nbclient.exceptions.CellExecutionError as exc:
        pytest.fail(f"{path.name}: {str(exc).splitlines()[-1] if str(exc) else exc}")
