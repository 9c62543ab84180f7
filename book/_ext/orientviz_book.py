"""Sphinx extension of the orientviz book: static widget and viewer snapshots, clear build errors.

Two things myst-nb does not do on its own:

* **Widgets without a kernel.** An executed notebook stores the state of every widget
  in its metadata, including what each ``ipywidgets.Output`` showed (figures, printed
  text). A live widget needs a kernel and the widget JavaScript, which an offline book
  has neither of, so :func:`render_widget_view` replaces each widget output by a
  *static snapshot*: the figures and text its Output widgets held when the cell ran,
  with the control settings as a caption. This works for every widget, the lesson
  apps of :mod:`orientviz.widgets` as well as ``ipywidgets.interact`` cells.
* **The live viewer.** A lesson cell that runs :func:`orientviz.viewer.live.show_live`
  shows the viser viewer as an IFrame of a server in the kernel; the book has no server,
  so :func:`_render_mime_type` shows the static picture named in the output's metadata
  (``book/_static/lesson_viewer/<name>.png``, written by ``tools/make_lesson_snapshots.py``).
* **A stalled execution.** :func:`patch_shell_polling` works around a lost wake-up in
  nbclient's handling of Output widgets that could stall a lesson for minutes.
* **Failing notebooks.** With ``nb_execution_raise_on_error = True`` myst-nb stops
  the build with the notebook path only; :func:`describe_failure` adds the cell
  number, its first line and the error, and the build stops with that message
  (a :class:`NotebookExecutionFailed`, which Sphinx prints without a traceback).
"""

from __future__ import annotations

import html
import re
from html.parser import HTMLParser
from pathlib import Path
from typing import Any

from docutils import nodes
from sphinx.errors import SphinxError

WIDGET_STATE = "application/vnd.jupyter.widget-state+json"
WIDGET_VIEW = "application/vnd.jupyter.widget-view+json"
#: CSS class of the container holding one widget snapshot in the HTML.
SNAPSHOT_CLASS = "orientviz-widget-snapshot"
_ANSI = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")
_TAG = re.compile(r"<[^>]+>")


# --------------------------------------------------------------------------- snapshots
def widget_states(metadata: dict) -> dict[str, dict]:
    """The widget models saved in a notebook's metadata: model id → model record."""
    return (metadata.get("widgets") or {}).get(WIDGET_STATE, {}).get("state", {}) or {}


def _child_ids(state: dict) -> list[str]:
    kids = state.get("children") or []
    return [
        k[len("IPY_MODEL_") :] for k in kids if isinstance(k, str) and k.startswith("IPY_MODEL_")
    ]


def _control_setting(model: dict) -> str | None:
    """``"description = value"`` for a slider, menu, toggle or checkbox; else None."""
    s = model.get("state", {})
    name = model.get("model_name", "")
    label = (s.get("description") or "").strip()
    if "_options_labels" in s and "index" in s:
        index = s["index"]
        labels = s["_options_labels"]
        if isinstance(index, int) and 0 <= index < len(labels):
            value = labels[index]
        else:
            return None
    elif name.endswith(("SliderModel", "TextModel")) or name in (
        "CheckboxModel",
        "ToggleButtonModel",
    ):
        value = s.get("value")
        if isinstance(value, float):
            value = f"{value:.6g}"
        elif isinstance(value, list):  # range sliders
            value = " – ".join(f"{v:.6g}" if isinstance(v, float) else str(v) for v in value)
    else:
        return None
    return f"{label} = {value}" if label else str(value)


def snapshot_of(states: dict[str, dict], model_id: str) -> tuple[list[dict], list[str], list[str]]:
    """Walk the widget tree below ``model_id``, in display order.

    Parameters
    ----------
    states : dict
        Model id → model record, as returned by :func:`widget_states`.
    model_id : str
        The widget a cell displayed.

    Returns
    -------
    outputs : list of dict
        nbformat outputs held by the Output widgets of the tree (streams merged).
    settings : list of str
        ``"description = value"`` of the controls.
    texts : list of str
        Text shown by HTML/Label/Textarea widgets (tags removed), e.g. a status line or log.
    """
    outputs: list[dict] = []
    settings: list[str] = []
    texts: list[str] = []
    seen: set[str] = set()

    def walk(mid: str) -> None:
        if mid in seen or mid not in states:
            return
        seen.add(mid)
        model = states[mid]
        s = model.get("state", {})
        name = model.get("model_name", "")
        if name == "OutputModel":
            outputs.extend(s.get("outputs") or [])
        elif name == "ImageModel":  # the picture is a binary buffer, saved base64-encoded
            mime = "image/" + {"jpg": "jpeg", "svg": "svg+xml"}.get(
                s.get("format"), s.get("format") or "png"
            )
            for buf in model.get("buffers") or []:
                if (
                    buf.get("path") == ["value"]
                    and buf.get("encoding") == "base64"
                    and buf.get("data")
                ):
                    outputs.append(
                        {"output_type": "display_data", "metadata": {}, "data": {mime: buf["data"]}}
                    )
        elif name in ("HTMLModel", "LabelModel", "TextareaModel", "HTMLMathModel"):
            text = html.unescape(_TAG.sub("", str(s.get("value") or ""))).strip()
            if text:
                texts.append(text)
        else:
            setting = _control_setting(model)
            if setting is not None:
                settings.append(setting)
        for kid in _child_ids(s):
            walk(kid)

    walk(model_id)
    return _merge_streams(outputs), settings, texts


def _merge_streams(outputs: list[dict]) -> list[dict]:
    merged: list[dict] = []
    for out in outputs:
        if (
            out.get("output_type") == "stream"
            and merged
            and merged[-1].get("output_type") == "stream"
            and merged[-1].get("name") == out.get("name")
        ):
            text = merged[-1]["text"]
            merged[-1] = dict(
                merged[-1],
                text=(text if isinstance(text, str) else "".join(text))
                + (out["text"] if isinstance(out["text"], str) else "".join(out["text"])),
            )
        else:
            merged.append(dict(out))
    for out in merged:
        if out.get("output_type") == "stream" and not isinstance(out.get("text"), str):
            out["text"] = "".join(out.get("text") or [])
    return merged


def snapshot_errors(outputs: list[dict]) -> list[str]:
    """``"Name: value"`` of every error output among a widget's outputs.

    An exception inside a widget callback does not fail its cell: the Output widget keeps
    the traceback, and the snapshot would show it on the built page. The book refuses to
    build instead (:func:`_render_widget_view`), naming the notebook and the cell.
    """
    return [
        f"{o.get('ename', 'Error')}: {o.get('evalue', '')}"
        for o in outputs
        if o.get("output_type") == "error"
    ]


#: Mime types a snapshot may show, best first (never a nested live widget).
SNAPSHOT_MIME = (
    "image/svg+xml",
    "image/png",
    "image/jpeg",
    "text/html",
    "text/markdown",
    "text/latex",
    "text/plain",
)


def _render_widget_view(self, data) -> list[nodes.Element]:
    """myst-nb hook: a static snapshot in place of a widget (falls back to the original)."""
    from myst_nb.core.render import MimeData

    content = data.content if isinstance(data.content, dict) else {}
    model_id = content.get("model_id", "")
    client = getattr(self.renderer, "nb_client", None)
    states = widget_states(getattr(client, "nb_metadata", {}) or {}) if client else {}
    if model_id not in states:
        return _ORIGINAL["render_widget_view"](self, data)
    outputs, settings, texts = snapshot_of(states, model_id)
    failed = snapshot_errors(outputs)
    if failed:
        document = getattr(self.renderer, "document", None)
        source = document.get("source", "?") if document is not None else "?"
        raise NotebookExecutionFailed(
            f"{source}\n  cell {data.cell_index}: a widget's output area holds an error "
            f"(the cell itself ran): {failed[0]}"
        )
    box = nodes.container(classes=[SNAPSHOT_CLASS])
    caption = "Static snapshot of an interactive widget (run the notebook to use it)"
    if settings:
        caption += ": " + "; ".join(settings)
    para = nodes.paragraph(classes=["orientviz-widget-caption"])
    para += nodes.emphasis(text=caption + ".")
    box += para
    for k, out in enumerate(outputs):
        kind = out.get("output_type")
        if kind == "stream" and out.get("name") == "stdout":
            box.extend(self.render_stdout(out, data.cell_metadata, data.cell_index, data.line))
        elif kind == "stream":
            box.extend(self.render_stderr(out, data.cell_metadata, data.cell_index, data.line))
        elif kind == "error":
            box.extend(self.render_error(out, data.cell_metadata, data.cell_index, data.line))
        elif kind in ("display_data", "execute_result"):
            bundle = out.get("data", {})
            mime = next((m for m in SNAPSHOT_MIME if m in bundle), None)
            if mime is None:
                continue
            box.extend(
                self.render_mime_type(
                    MimeData(
                        mime,
                        bundle[mime],
                        cell_metadata=data.cell_metadata,
                        output_metadata=out.get("metadata", {}),
                        cell_index=data.cell_index,
                        output_index=k,
                        line=data.line,
                    )
                )
            )
    for text in texts:
        block = nodes.literal_block(text, text, classes=["output", "stream"])
        block["language"] = "text"  # a status line or log, not code
        box += block
    return [box]


# --------------------------------------------------------------------------- live viewer
#: output metadata key of a live viewer (orientviz.viewer.live.SNAPSHOT_KEY; not imported
#: here so that the extension loads without the viewer's dependencies)
VIEWER_SNAPSHOT_KEY = "orientviz_viewer_snapshot"
#: folder (below the book's source) of the lessons' viewer pictures
LESSON_SNAPSHOTS = Path("_static") / "lesson_viewer"
#: CSS class of the container holding a viewer picture in the HTML.
VIEWER_CLASS = "orientviz-viewer-snapshot"


def viewer_snapshot_path(srcdir: str | Path, name: str) -> Path:
    """The picture that stands for the live viewer output ``name`` in the book."""
    return Path(srcdir) / LESSON_SNAPSHOTS / f"{name}.png"


def _render_mime_type(self, data) -> list[nodes.Element]:
    """myst-nb hook: a live viewer's output becomes its static picture; others unchanged."""
    name = (data.output_metadata or {}).get(VIEWER_SNAPSHOT_KEY)
    if not name:
        return _ORIGINAL["render_mime_type"](self, data)
    document = getattr(self.renderer, "document", None)
    source = document.get("source", "?") if document is not None else "?"
    env = getattr(getattr(document, "settings", None), "env", None)
    srcdir = getattr(env, "srcdir", None) or Path(__file__).resolve().parents[1]
    path = viewer_snapshot_path(srcdir, str(name))
    if not path.is_file():
        raise NotebookExecutionFailed(
            f"{source}\n  cell {data.cell_index}: no picture of the live viewer {name!r} at "
            f"{path} (python tools/make_lesson_snapshots.py writes it)"
        )
    box = nodes.container(classes=[VIEWER_CLASS])
    para = nodes.paragraph(classes=["orientviz-widget-caption"])
    para += nodes.emphasis(
        text="Static picture of the live 3D viewer (in JupyterLab this cell shows the viewer "
        "itself, on the state computed above: turn the scene, use the panel)."
    )
    box += para
    uri = "/" + (LESSON_SNAPSHOTS / f"{name}.png").as_posix()
    box += nodes.image(uri=uri, alt=f"orientviz viewer: {name}", classes=["orientviz-viewer"])
    return [box]


# --------------------------------------------------------------------------- failures
class NotebookExecutionFailed(SphinxError):
    """A lesson notebook raised while the book was being built."""

    category = "Notebook execution failed"


def _failing_cell(notebook, err: BaseException | None) -> int | None:
    """Index of the cell that failed: the one with an error output, else the one whose
    source the error message quotes, else the last cell that started executing."""
    cells = notebook.get("cells", [])
    for i, cell in enumerate(cells):
        if any(o.get("output_type") == "error" for o in cell.get("outputs", [])):
            return i
    message = str(err or "")
    for i, cell in enumerate(cells):
        src = "".join(cell.get("source", "")).strip()
        if cell.get("cell_type") == "code" and src and src in message:
            return i
    started = [i for i, c in enumerate(cells) if c.get("execution_count")]
    return started[-1] if started else None


def describe_failure(path: str | Path, notebook, err: BaseException | None) -> str:
    """One message naming the notebook, the cell (index and first line) and the error.

    Parameters
    ----------
    path : str or Path
        The notebook file.
    notebook : dict or nbformat.NotebookNode
        The notebook as executed up to the failure (outputs filled in place).
    err : BaseException or None
        What the execution raised (nbclient's ``CellExecutionError``,
        ``CellTimeoutError``, ``DeadKernelError``...).

    Returns
    -------
    str
    """
    cells = notebook.get("cells", [])
    index = _failing_cell(notebook, err)
    if err is not None and getattr(err, "ename", None):
        what = f"{err.ename}: {err.evalue}"
    elif err is not None:
        first_line = next((ln for ln in str(err).splitlines() if ln.strip()), "")
        what = f"{type(err).__name__}: {first_line.strip()}"
    else:
        what = "unknown error"
    lines = [f"{Path(path)}"]
    if index is None:
        lines.append(f"  cell: unknown — {what}")
    else:
        cell = cells[index]
        source = "".join(cell.get("source", ""))
        first = next((ln for ln in source.splitlines() if ln.strip()), "").strip()
        code_no = sum(1 for c in cells[: index + 1] if c.get("cell_type") == "code")
        lines.append(f"  cell {index} (code cell {code_no}; counting every cell from 0)")
        lines.append(f"  first line: {first}")
        lines.append(f"  error: {what}")
        for out in cell.get("outputs", []):
            if out.get("output_type") == "error":
                tb = _ANSI.sub("", "\n".join(out.get("traceback", [])))
                tail = [ln for ln in tb.splitlines() if ln.strip()][-12:]
                lines.append("  traceback (last lines):")
                lines.extend("    " + ln for ln in tail)
    return "\n".join(lines)


def _start_client(self):
    from myst_nb.core.execute.base import ExecutionError

    try:
        return _ORIGINAL["start_client"](self)
    except ExecutionError as exc:
        raise NotebookExecutionFailed(
            describe_failure(self.path, self.notebook, exc.__cause__)
        ) from exc


# --------------------------------------------------------------------------- a stall
#: Longest single wait (s) for a reply on the kernel's shell channel, see _sliced_get_msg.
POLL_SLICE_S = 1.0


async def _sliced_get_msg(self, timeout: float | None = None):
    """Wait for a shell message in short polls instead of one long one.

    nbclient mirrors Output widgets by *sending* state updates on the shell channel
    while it *waits* on the same channel for the cell's execute_reply. With ZeroMQ's
    edge-triggered notifications the send can swallow the wake-up of the wait: the
    reply is there, but the poll sleeps until its timeout (nb_execution_timeout, 300 s)
    and only then finds it (jupyter/nbclient#312). Lesson cells with widget apps
    stalled the book build this way for ~300 s in two builds out of four. Polling in
    slices of POLL_SLICE_S bounds such a stall to about a second; a real timeout is
    still reported at the original deadline.
    """
    from queue import Empty
    from time import monotonic

    deadline = None if timeout is None else monotonic() + timeout
    while True:
        step = (
            POLL_SLICE_S
            if deadline is None
            else min(POLL_SLICE_S, max(0.0, deadline - monotonic()))
        )
        try:
            return await _ORIGINAL["get_msg"](self, timeout=step)
        except Empty:
            if deadline is not None and monotonic() >= deadline:
                raise


_ORIGINAL: dict[str, Any] = {}


def patch_shell_polling() -> None:
    """Install :func:`_sliced_get_msg` on jupyter_client's asyncio channel (idempotent)."""
    from jupyter_client.channels import AsyncZMQSocketChannel

    if "get_msg" not in _ORIGINAL:
        _ORIGINAL["get_msg"] = AsyncZMQSocketChannel.get_msg
        AsyncZMQSocketChannel.get_msg = _sliced_get_msg


def _patch() -> None:
    from myst_nb.core.execute.direct import NotebookClientDirect
    from myst_nb.core.render import NbElementRenderer

    if "render_widget_view" not in _ORIGINAL:
        _ORIGINAL["render_widget_view"] = NbElementRenderer.render_widget_view
        _ORIGINAL["render_mime_type"] = NbElementRenderer.render_mime_type
        _ORIGINAL["start_client"] = NotebookClientDirect.start_client
        NbElementRenderer.render_widget_view = _render_widget_view
        NbElementRenderer.render_mime_type = _render_mime_type
        NotebookClientDirect.start_client = _start_client
    patch_shell_polling()


class _SnapshotFinder(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=False)
        self.found: list[list[str]] = []
        self.depth = 0  # div nesting inside the current snapshot; 0 = outside

    def handle_starttag(self, tag, attrs):
        classes = (dict(attrs).get("class") or "").split()
        if self.depth == 0 and tag == "div" and SNAPSHOT_CLASS in classes:
            self.found.append([])
            self.depth = 1
            return
        if self.depth:
            self.depth += tag == "div"
            self.found[-1].append(self.get_starttag_text() or "")

    def handle_endtag(self, tag):
        if self.depth:
            self.depth -= tag == "div"
            if self.depth:
                self.found[-1].append(f"</{tag}>")

    def handle_data(self, data):
        if self.depth:
            self.found[-1].append(data)


def find_snapshots(page_html: str) -> list[str]:
    """The inner HTML of each widget snapshot on a built page (for tests and checks)."""
    finder = _SnapshotFinder()
    finder.feed(page_html)
    return ["".join(parts) for parts in finder.found]


def setup(app) -> dict:
    """Register the extension (patches myst-nb's widget renderer and direct executor)."""
    _patch()
    app.add_css_file("orientviz_book.css")
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
