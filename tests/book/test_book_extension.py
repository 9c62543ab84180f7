"""The book's Sphinx extension (book/_ext/orientviz_book.py): widget snapshots and the
message of a failing notebook."""

from __future__ import annotations

import importlib.util
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).parents[2]
pytest.importorskip("sphinx")
_spec = importlib.util.spec_from_file_location(
    "orientviz_book", ROOT / "book/_ext/orientviz_book.py"
)
ob = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(ob)


def _model(name, **state):
    return {"model_name": name, "model_module": "@jupyter-widgets/controls", "state": state}


def _states():
    """An HBox(VBox(slider, dropdown, checkbox, html), Output(figure)) and an unrelated Output."""
    png = {"image/png": "iVBORw0KGgo=", "text/plain": "<Figure>"}
    return {
        "box": _model("HBoxModel", children=["IPY_MODEL_controls", "IPY_MODEL_out"]),
        "controls": _model(
            "VBoxModel",
            children=[
                "IPY_MODEL_slider",
                "IPY_MODEL_menu",
                "IPY_MODEL_check",
                "IPY_MODEL_html",
                "IPY_MODEL_text",
            ],
        ),
        "slider": _model("FloatSliderModel", description="σ [cm]", value=5.0),
        "menu": _model(
            "DropdownModel",
            description="control",
            index=1,
            _options_labels=["corners", "perimeter"],
        ),
        "check": _model("CheckboxModel", description="rigid", value=False),
        "html": _model("HTMLModel", value="rms parallax: <b>12 µm</b>"),
        "text": _model(
            "OutputModel",
            outputs=[
                {"output_type": "stream", "name": "stdout", "text": "line 1\n"},
                {"output_type": "stream", "name": "stdout", "text": ["line ", "2\n"]},
            ],
        ),
        "out": _model(
            "OutputModel", outputs=[{"output_type": "display_data", "data": png, "metadata": {}}]
        ),
        "other": _model(
            "OutputModel",
            outputs=[{"output_type": "stream", "name": "stdout", "text": "not ours\n"}],
        ),
    }


def test_snapshot_collects_outputs_settings_and_text_in_display_order():
    outputs, settings, texts = ob.snapshot_of(_states(), "box")
    assert settings == ["σ [cm] = 5", "control = perimeter", "rigid = False"]
    assert texts == ["rms parallax: 12 µm"]
    # the two stdout chunks are merged; the figure follows; the unrelated Output is not in it
    assert [o["output_type"] for o in outputs] == ["stream", "display_data"]
    assert outputs[0]["text"] == "line 1\nline 2\n"
    assert "image/png" in outputs[1]["data"]


def test_snapshot_shows_an_image_widget_from_its_saved_buffer():
    states = _states()
    states["out"] = {
        "model_name": "ImageModel",
        "state": {"format": "png", "layout": "IPY_MODEL_x"},
        "buffers": [{"data": "iVBORw0KGgo=", "encoding": "base64", "path": ["value"]}],
    }
    outputs, _, _ = ob.snapshot_of(states, "box")
    assert outputs[-1]["output_type"] == "display_data"
    assert outputs[-1]["data"] == {"image/png": "iVBORw0KGgo="}


def test_snapshot_of_unknown_or_cyclic_widgets_terminates():
    states = _states()
    states["controls"]["state"]["children"].append("IPY_MODEL_box")  # a cycle
    states["controls"]["state"]["children"].append("IPY_MODEL_missing")
    outputs, _, _ = ob.snapshot_of(states, "box")
    assert len(outputs) == 2
    assert ob.snapshot_of(states, "nope") == ([], [], [])


def test_widget_states_reads_notebook_metadata():
    meta = {"widgets": {ob.WIDGET_STATE: {"state": _states(), "version_major": 2}}}
    assert set(ob.widget_states(meta)) == set(_states())
    assert ob.widget_states({}) == {}


def test_find_snapshots_returns_the_inner_html_of_each_snapshot():
    page = (
        '<p>before</p><div class="cell_output docutils container">'
        f'<div class="{ob.SNAPSHOT_CLASS} docutils container"><p>cap</p>'
        '<div class="highlight"><pre>text</pre></div><img src="a.png"/></div></div>'
        f'<div class="{ob.SNAPSHOT_CLASS}"><p>second</p></div><p>after <img src="b.png"/></p>'
    )
    found = ob.find_snapshots(page)
    assert len(found) == 2
    assert "<img" in found[0] and "<pre>" in found[0] and "before" not in found[0]
    assert "second" in found[1] and "<img" not in found[1] and "after" not in found[1]


def _notebook(sources):
    return {
        "cells": [
            {"cell_type": "markdown", "source": "# title", "metadata": {}},
            *(
                {
                    "cell_type": "code",
                    "source": s,
                    "metadata": {},
                    "outputs": [],
                    "execution_count": None,
                }
                for s in sources
            ),
        ]
    }


def test_describe_failure_names_the_cell_with_the_error_output():
    nb = _notebook(["import math", "\n\nvalue = math.sqrt(-1)  # boom\nprint(value)", "print(2)"])
    nb["cells"][2]["outputs"] = [
        {
            "output_type": "error",
            "ename": "ValueError",
            "evalue": "math domain error",
            "traceback": ["\x1b[0;31mValueError\x1b[0m: math domain error"],
        }
    ]

    class Err(Exception):
        ename, evalue = "ValueError", "math domain error"

    msg = ob.describe_failure("lessons/99_x.ipynb", nb, Err())
    assert "99_x.ipynb" in msg
    assert "cell 2 (code cell 2" in msg
    assert "first line: value = math.sqrt(-1)  # boom" in msg
    assert "ValueError: math domain error" in msg
    assert "\x1b" not in msg  # colour codes stripped from the traceback


def test_describe_failure_of_a_timeout_finds_the_cell_by_its_source():
    nb = _notebook(["x = 1", "import time\ntime.sleep(1000)"])
    err = TimeoutError(
        "A cell timed out while it was being executed, after 5 seconds.\n"
        "Here is a preview of the cell contents:\n-------------------\n"
        "import time\ntime.sleep(1000)\n-------------------"
    )
    msg = ob.describe_failure("a.ipynb", nb, err)
    assert "cell 2 (code cell 2" in msg and "first line: import time" in msg
    assert "TimeoutError" in msg


@pytest.mark.slow
def test_failing_book_build_names_notebook_and_cell(tmp_path):
    """A throwaway book whose notebook raises in its second code cell (~10 s)."""
    pytest.importorskip("myst_nb")
    nbformat = pytest.importorskip("nbformat")
    src = tmp_path / "src"
    src.mkdir()
    (src / "conf.py").write_text(
        f"import sys\nsys.path.insert(0, {str(ROOT / 'book/_ext')!r})\n"
        # as book/conf.py: jsonschema without its format checkers' packages before myst-nb
        "from orientviz.io.jsonio import import_jsonschema\nimport_jsonschema()\n"
        "extensions = ['myst_nb', 'orientviz_book']\n"
        "nb_execution_mode = 'force'\nnb_execution_raise_on_error = True\n"
        "exclude_patterns = ['_build']\n",
        encoding="utf-8",
    )
    nb = nbformat.v4.new_notebook()
    nb.cells = [
        nbformat.v4.new_markdown_cell("# A broken lesson"),
        nbformat.v4.new_code_cell("x = 1"),
        nbformat.v4.new_code_cell("y = x / 0  # this cell fails\nprint(y)"),
        nbformat.v4.new_code_cell("print('never reached')"),
    ]
    nbformat.write(nb, src / "broken_lesson.ipynb")
    (src / "index.md").write_text("# Index\n\n```{toctree}\nbroken_lesson\n```\n", encoding="utf-8")
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-b", "html", "-q", str(src), str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode != 0
    err = proc.stderr
    assert "Notebook execution failed" in err
    assert "broken_lesson.ipynb" in err
    assert "cell 2 (code cell 2" in err
    assert "first line: y = x / 0  # this cell fails" in err
    assert "ZeroDivisionError" in err


def test_sliced_shell_polling_finds_a_late_message_and_keeps_the_deadline(monkeypatch):
    """The workaround for nbclient#312 polls in short slices but times out as before."""
    import asyncio
    import time
    from queue import Empty

    monkeypatch.setattr(ob, "POLL_SLICE_S", 0.05)
    calls = []

    async def fake_get_msg(self, timeout=None):
        calls.append(timeout)
        await asyncio.sleep(timeout)
        if self.ready_after is not None and len(calls) > self.ready_after:
            return {"msg": "reply"}
        raise Empty

    monkeypatch.setitem(ob._ORIGINAL, "get_msg", fake_get_msg)

    class Channel:
        def __init__(self, ready_after):
            self.ready_after = ready_after

    # the message shows up at the fourth short poll, long before the 5 s deadline
    t = time.monotonic()
    assert asyncio.run(ob._sliced_get_msg(Channel(3), timeout=5.0)) == {"msg": "reply"}
    assert time.monotonic() - t < 1.0
    assert len(calls) == 4 and max(calls) <= 0.05
    # no message at all: Empty at the deadline, not before
    calls.clear()
    t = time.monotonic()
    with pytest.raises(Empty):
        asyncio.run(ob._sliced_get_msg(Channel(None), timeout=0.3))
    assert 0.28 <= time.monotonic() - t < 1.0
    # no timeout: keeps polling until the message comes
    calls.clear()
    assert asyncio.run(ob._sliced_get_msg(Channel(2), timeout=None)) == {"msg": "reply"}


def test_an_error_inside_a_widget_is_found():
    outputs = [
        {"output_type": "stream", "name": "stdout", "text": "fine\n"},
        {
            "output_type": "error",
            "ename": "NameError",
            "evalue": "name 's' is not defined",
            "traceback": [],
        },
    ]
    assert ob.snapshot_errors(outputs) == ["NameError: name 's' is not defined"]
    assert ob.snapshot_errors(outputs[:1]) == []
