"""Write student copies of the lesson notebooks: every solution becomes a blank.

Usage::

    python -m orientviz.exercises.strip notebooks/ OUTDIR      # every *.ipynb in notebooks/
    python -m orientviz.exercises.strip notebooks/04_resection_and_intersection.ipynb OUTDIR

In code cells, the lines between ``### BEGIN SOLUTION`` and ``### END SOLUTION`` (markers
included) become one ``raise NotImplementedError`` at the marker's indentation. In markdown
cells, the text between ``<!-- BEGIN SOLUTION -->`` and ``<!-- END SOLUTION -->`` becomes
``*(your answer)*``. Solution cells lose their ``hide-cell`` tag and ``source_hidden`` flag
(the blank is for the student to fill), and all outputs are cleared.
"""

from __future__ import annotations

import json
import pathlib
import sys
from typing import Any

__all__ = ["BEGIN", "END", "MD_BEGIN", "MD_END", "main", "strip_notebook", "strip_source"]

BEGIN = "### BEGIN SOLUTION"
END = "### END SOLUTION"
MD_BEGIN = "<!-- BEGIN SOLUTION -->"
MD_END = "<!-- END SOLUTION -->"


def strip_source(source: str, markdown: bool = False) -> tuple[str, int]:
    """Replace each solution block of one cell's source.

    Parameters
    ----------
    source : str
        The cell's text.
    markdown : bool
        Whether the cell is markdown (HTML-comment markers) or code (``###`` markers).

    Returns
    -------
    (str, int)
        The stripped text and the number of blocks replaced.

    Raises
    ------
    ValueError
        If a block is opened and not closed (or closed without being opened).
    """
    begin, end = (MD_BEGIN, MD_END) if markdown else (BEGIN, END)
    out: list[str] = []
    inside = False
    count = 0
    for line in source.splitlines(keepends=True):
        stripped = line.strip()
        if stripped == begin:
            if inside:
                raise ValueError("nested BEGIN SOLUTION")
            inside = True
            count += 1
            indent = line[: len(line) - len(line.lstrip())]
            out.append("*(your answer)*\n" if markdown else f"{indent}raise NotImplementedError\n")
        elif stripped == end:
            if not inside:
                raise ValueError("END SOLUTION without BEGIN SOLUTION")
            inside = False
        elif not inside:
            out.append(line)
    if inside:
        raise ValueError("BEGIN SOLUTION without END SOLUTION")
    return "".join(out), count


def _source(cell: dict[str, Any]) -> str:
    src = cell.get("source", "")
    return "".join(src) if isinstance(src, list) else src


def strip_notebook(nb: dict[str, Any]) -> tuple[dict[str, Any], int]:
    """Return a student copy of a notebook (a JSON dict) and the number of blocks replaced."""
    total = 0
    cells = []
    for cell in nb.get("cells", []):
        cell = json.loads(json.dumps(cell))  # a deep copy
        text, n = strip_source(_source(cell), markdown=cell.get("cell_type") == "markdown")
        if n:
            total += n
            cell["source"] = text
            meta = cell.setdefault("metadata", {})
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
        if cell.get("cell_type") == "code":
            cell["outputs"] = []
            cell["execution_count"] = None
        cells.append(cell)
    out = dict(nb)
    out["cells"] = cells
    return out, total


def main(argv: list[str] | None = None) -> int:
    """Command line: ``strip SRC OUTDIR`` (SRC a notebook or a folder of notebooks)."""
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 2:
        print(
            "usage: python -m orientviz.exercises.strip SRC(.ipynb or folder) OUTDIR",
            file=sys.stderr,
        )
        return 2
    src, outdir = pathlib.Path(args[0]), pathlib.Path(args[1])
    paths = sorted(src.glob("*.ipynb")) if src.is_dir() else [src]
    if not paths or not all(p.is_file() for p in paths):
        print(f"strip: no notebooks at {src}", file=sys.stderr)
        return 1
    if outdir.resolve() == (src if src.is_dir() else src.parent).resolve():
        print("strip: OUTDIR must differ from the source folder", file=sys.stderr)
        return 1
    outdir.mkdir(parents=True, exist_ok=True)
    for path in paths:
        try:
            nb = json.loads(path.read_text(encoding="utf-8"))
            student, n = strip_notebook(nb)
        except (ValueError, json.JSONDecodeError) as exc:
            print(f"strip: {path}: {exc}", file=sys.stderr)
            return 1
        target = outdir / path.name
        tmp = target.with_suffix(".ipynb.tmp")
        tmp.write_text(json.dumps(student, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
        tmp.replace(target)
        print(f"{target}: {n} solution{'s' if n != 1 else ''} blanked")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
