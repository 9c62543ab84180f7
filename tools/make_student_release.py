"""Write the student release of the lesson notebooks: every solution becomes a blank.

Usage::

    python tools/make_student_release.py notebooks/ release/      # every *.ipynb in notebooks/
    python tools/make_student_release.py notebooks/09_datum.ipynb release/

The lessons in ``notebooks/`` are the teacher's source, marked the way nbgrader and
otter-grader read them:

* in code cells, the lines between ``### BEGIN SOLUTION`` and ``### END SOLUTION``
  (markers included) become one ``raise NotImplementedError`` at the marker's indentation;
* the lines between ``### BEGIN HIDDEN TESTS`` and ``### END HIDDEN TESTS`` are removed
  (they run in the teacher's copy and when grading, the student never sees them); a code cell
  left empty by that says so in a comment;
* in markdown cells, the text between ``<!-- BEGIN SOLUTION -->`` and
  ``<!-- END SOLUTION -->`` becomes ``*(your answer)*``.

Solution cells lose their ``hide-cell`` tag and ``source_hidden`` flag (the blank is for the
student to fill). The check cell after a blanked solution gets the tag ``raises-exception``,
so that "Run All" (Jupyter Notebook, JupyterLab, nbclient, nbgrader's autograde) goes on past
a check that answers "not written yet"; the lesson's later cells fall back to the library's
result while the student's function is a blank. All outputs are cleared. The first code cell
gets one call of ``orientviz.exercises.release_check`` with the checks the lesson calls and
the commit the release is made from: a release run against another orientviz stops there
with a message that says so.

The installed package holds the checks only (``orientviz.exercises``); the solutions are in
the lessons and in ``tests/exercises/answers``, neither of which is in the wheel.
"""

from __future__ import annotations

import json
import pathlib
import re
import subprocess
import sys
from typing import Any

__all__ = [
    "BEGIN",
    "END",
    "HIDDEN_BEGIN",
    "HIDDEN_END",
    "MD_BEGIN",
    "MD_END",
    "main",
    "release_notebook",
    "strip_source",
]

BEGIN = "### BEGIN SOLUTION"
END = "### END SOLUTION"
HIDDEN_BEGIN = "### BEGIN HIDDEN TESTS"
HIDDEN_END = "### END HIDDEN TESTS"
MD_BEGIN = "<!-- BEGIN SOLUTION -->"
MD_END = "<!-- END SOLUTION -->"
BLANK = "raise NotImplementedError"
MD_BLANK = "*(your answer)*"
CHECK_TAG = "raises-exception"
HIDDEN_NOTE = (
    "# (the teacher's hidden tests of the check above run here when the lesson is graded)\n"
)


def _blocks(source: str, begin: str, end: str, replacement: str | None) -> tuple[str, int]:
    """Replace each ``begin``…``end`` block by ``replacement`` (indented), or drop it (None)."""
    out: list[str] = []
    inside = False
    count = 0
    for line in source.splitlines(keepends=True):
        stripped = line.strip()
        if stripped == begin:
            if inside:
                raise ValueError(f"nested {begin!r}")
            inside = True
            count += 1
            if replacement is not None:
                indent = line[: len(line) - len(line.lstrip())]
                out.append(f"{indent}{replacement}\n")
        elif stripped == end:
            if not inside:
                raise ValueError(f"{end!r} without {begin!r}")
            inside = False
        elif not inside:
            out.append(line)
    if inside:
        raise ValueError(f"{begin!r} without {end!r}")
    return "".join(out), count


def strip_source(source: str, markdown: bool = False) -> tuple[str, int]:
    """Blank each solution block of one cell's source (and drop its hidden tests).

    Parameters
    ----------
    source : str
        The cell's text.
    markdown : bool
        Whether the cell is markdown (HTML-comment markers) or code (``###`` markers).

    Returns
    -------
    (str, int)
        The student's text and the number of solution blocks blanked.

    Raises
    ------
    ValueError
        If a block is opened and not closed (or closed without being opened).
    """
    if markdown:
        return _blocks(source, MD_BEGIN, MD_END, MD_BLANK)
    text, _ = _blocks(source, HIDDEN_BEGIN, HIDDEN_END, None)
    return _blocks(text, BEGIN, END, BLANK)


def _source(cell: dict[str, Any]) -> str:
    src = cell.get("source", "")
    return "".join(src) if isinstance(src, list) else src


def _unhide(meta: dict[str, Any]) -> None:
    tags = [t for t in meta.get("tags", []) if t != "hide-cell"]
    if tags:
        meta["tags"] = tags
    else:
        meta.pop("tags", None)
    meta.pop("mystnb", None)
    if isinstance(meta.get("jupyter"), dict):
        meta["jupyter"].pop("source_hidden", None)
        if not meta["jupyter"]:
            meta.pop("jupyter")


def _checks_called(nb: dict[str, Any]) -> list[str]:
    """The ``check_*`` names the notebook's code cells call."""
    names: set[str] = set()
    other: set[str] = set()  # the lesson's own helpers and other packages' functions
    for cell in nb.get("cells", []):
        if cell.get("cell_type") == "code":
            src = _source(cell)
            names |= set(re.findall(r"\b(check_\w+)\(", src))
            other |= set(re.findall(r"\bdef (check_\w+)\(", src))
            for module, group, line in re.findall(
                r"from\s+([\w.]+)\s+import\s+(?:\(([^)]*)\)|([^\n]*))", src
            ):
                if not module.startswith("orientviz.exercises"):
                    other |= set(re.findall(r"\b(check_\w+)\b", group + line))
    return sorted(names - other)


def _guard(nb: dict[str, Any], lesson: str, made_with: str) -> None:
    """Append the release check to the first code cell (no cell is added: numbers stay)."""
    for cell in nb.get("cells", []):
        if cell.get("cell_type") == "code":
            text = _source(cell).rstrip("\n")
            cell["source"] = (
                f"{text}\n\nfrom orientviz.exercises import release_check  # the release matches"
                f" the installed orientviz\nrelease_check({lesson!r}, {_checks_called(nb)!r},"
                f" made_with={made_with!r})\n"
            )
            return


def release_notebook(
    nb: dict[str, Any], lesson: str | None = None, made_with: str = ""
) -> tuple[dict[str, Any], int]:
    """Return the student copy of a notebook (a JSON dict) and the number of blocks blanked.

    With ``lesson`` (e.g. ``"05"``) the first code cell also calls
    :func:`orientviz.exercises.release_check` with the checks the lesson calls and
    ``made_with`` (the orientviz commit the release is made from).
    """
    total = 0
    cells = []
    check_next = False
    for cell in nb.get("cells", []):
        cell = json.loads(json.dumps(cell))  # a deep copy
        code = cell.get("cell_type") == "code"
        text, n = strip_source(_source(cell), markdown=not code)
        if code and _source(cell).strip() and not text.strip():  # a cell of hidden tests only
            text = HIDDEN_NOTE
        meta = cell.setdefault("metadata", {})
        if text != _source(cell):
            cell["source"] = text
        if n:
            total += n
            _unhide(meta)
        if code:
            if check_next and not n and text.strip():
                tags = meta.setdefault("tags", [])
                if CHECK_TAG not in tags:
                    tags.append(CHECK_TAG)
            check_next = bool(n) or (check_next and not text.strip())
            cell["outputs"] = []
            cell["execution_count"] = None
        cells.append(cell)
    out = dict(nb)
    out["cells"] = cells
    if lesson is not None:
        _guard(out, lesson, made_with)
    return out, total


def _commit(path: pathlib.Path) -> str:
    """The short git commit of the repository holding ``path`` ("" outside a repository)."""
    try:
        out = subprocess.run(
            ["git", "-C", str(path), "rev-parse", "--short", "HEAD"],
            capture_output=True, text=True, check=True, timeout=10,
        )  # fmt: skip
    except (OSError, subprocess.SubprocessError):
        return ""
    return out.stdout.strip()


def main(argv: list[str] | None = None) -> int:
    """Command line: ``make_student_release.py SRC OUTDIR`` (SRC a notebook or a folder)."""
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 2:
        print(
            "usage: python tools/make_student_release.py SRC(.ipynb or folder) OUTDIR",
            file=sys.stderr,
        )
        return 2
    src, outdir = pathlib.Path(args[0]), pathlib.Path(args[1])
    paths = sorted(src.glob("*.ipynb")) if src.is_dir() else [src]
    if not paths or not all(p.is_file() for p in paths):
        print(f"release: no notebooks at {src}", file=sys.stderr)
        return 1
    if outdir.resolve() == (src if src.is_dir() else src.parent).resolve():
        print("release: OUTDIR must differ from the source folder", file=sys.stderr)
        return 1
    outdir.mkdir(parents=True, exist_ok=True)
    made_with = _commit(paths[0].parent)
    for path in paths:
        try:
            nb = json.loads(path.read_text(encoding="utf-8"))
            lesson = path.name[:2] if path.name[:2].isdigit() else None
            student, n = release_notebook(nb, lesson, made_with)
        except (ValueError, json.JSONDecodeError) as exc:
            print(f"release: {path}: {exc}", file=sys.stderr)
            return 1
        target = outdir / path.name
        tmp = target.with_suffix(".ipynb.tmp")
        tmp.write_text(json.dumps(student, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
        tmp.replace(target)
        print(f"{target}: {n} solution{'s' if n != 1 else ''} blanked")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
