"""Lint of the lesson shape (issue #13, /work/shared/LESSON-PATTERN.md).

Every lesson notebook not in ``PENDING`` must have:

* a "Goals and prerequisites" section first (naming the time needed) and a "Summary" last;
* at least 3 display equations (``$$ … $$``) in its markdown and a symbol table
  (``| symbol | code | unit | meaning |``);
* a "Your version" section with a hidden solution (the student writes the method);
* an "Exercises" section with at least 3 hidden solutions;
* every solution cell hidden (tag ``hide-cell``, ``mystnb.code_prompt_show``,
  ``jupyter.source_hidden``) and followed by a visible code cell (the check);
* no ``raises-exception`` cell, no iframe to a server, and every "lesson NN" naming a notebook.

``PENDING`` lists the notebooks not yet converted; each lesson engineer removes theirs when
done. A pending notebook that already passes fails the ratchet test (remove it then).
"""

from __future__ import annotations

import json
import pathlib
import re

import pytest
from release_tool import release

ROOT = pathlib.Path(__file__).parents[2]
BEGIN = release.BEGIN
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))

#: Notebooks (stems) not yet converted to the lesson shape. Shrink it; never grow it.
PENDING = {}

DISPLAY = re.compile(r"\$\$(.+?)\$\$", re.S)
SYMBOL_TABLE = re.compile(r"^\|\s*symbol\s*\|\s*code\s*\|\s*unit\s*\|\s*meaning\s*\|", re.I | re.M)
TIME = re.compile(r"\b\d+\s*(?:–\s*\d+\s*)?(?:min|minutes|h|hours?)\b", re.I)


def _source(cell: dict) -> str:
    src = cell.get("source", "")
    return "".join(src) if isinstance(src, list) else src


def _headings(text: str) -> list[tuple[int, str]]:
    """Markdown headings (level, text) outside fenced code."""
    out, fenced = [], False
    for line in text.splitlines():
        if line.lstrip().startswith("```"):
            fenced = not fenced
        elif not fenced and (m := re.match(r"^(#{1,6})\s+(.*)$", line)):
            out.append((len(m.group(1)), m.group(2).strip()))
    return out


def _is_hidden(cell: dict) -> bool:
    meta = cell.get("metadata", {})
    return (
        "hide-cell" in meta.get("tags", [])
        and bool(meta.get("mystnb", {}).get("code_prompt_show"))
        and meta.get("jupyter", {}).get("source_hidden") is True
    )


def lint(nb: dict) -> list[str]:
    """Return the lesson-shape problems of one notebook (empty if it has the shape)."""
    cells = nb["cells"]
    problems: list[str] = []
    md = "\n".join(_source(c) for c in cells if c["cell_type"] == "markdown")

    # sections, in cell order: (cell index, level, text)
    sections = [
        (i, lvl, txt)
        for i, c in enumerate(cells)
        if c["cell_type"] == "markdown"
        for lvl, txt in _headings(_source(c))
    ]
    level2 = [s for s in sections if s[1] == 2]
    if (
        not level2
        or not re.search(r"goals", level2[0][2], re.I)
        or not re.search(r"prerequisit", level2[0][2], re.I)
    ):
        problems.append("the first section (##) must be 'Goals and prerequisites'")
    else:
        start = level2[0][0]
        end = level2[1][0] if len(level2) > 1 else len(cells)
        goals = "\n".join(_source(c) for c in cells[start:end] if c["cell_type"] == "markdown")
        if not TIME.search(goals):
            problems.append("the goals section must say the time needed (e.g. '45 min')")
    if not level2 or not re.search(r"summary", level2[-1][2], re.I):
        problems.append("the last section (##) must be 'Summary'")

    n_display = len(DISPLAY.findall(md))
    if n_display < 3:
        problems.append(f"{n_display} display equations ($$…$$), at least 3 needed")
    if not SYMBOL_TABLE.search(md):
        problems.append("no symbol table (| symbol | code | unit | meaning |)")

    solutions = [i for i, c in enumerate(cells) if c["cell_type"] == "code" and BEGIN in _source(c)]
    for i in solutions:
        if not _is_hidden(cells[i]):
            problems.append(
                f"cell {i}: solution not hidden (tag hide-cell, mystnb.code_prompt_show, jupyter.source_hidden)"
            )
        nxt = next((j for j in range(i + 1, len(cells)) if cells[j]["cell_type"] == "code"), None)
        if nxt is None or BEGIN in _source(cells[nxt]) or _is_hidden(cells[nxt]):
            problems.append(f"cell {i}: a solution must be followed by a visible check cell")

    def _solutions_in(pattern: str) -> int | None:
        for k, (i, lvl, txt) in enumerate(sections):
            if re.search(pattern, txt, re.I):
                end = next((j for j, l2, _ in sections[k + 1 :] if l2 <= lvl), len(cells))
                return sum(i < s < end for s in solutions)
        return None

    yours = _solutions_in(r"your version")
    if yours is None:
        problems.append("no 'Your version' section")
    elif yours < 1:
        problems.append("the 'Your version' section has no hidden solution")
    exercises = _solutions_in(r"^exercises\b")
    if exercises is None:
        problems.append("no 'Exercises' section")
    elif exercises < 3:
        problems.append(f"{exercises} exercises with hidden solutions, at least 3 needed")

    numbers = {p.stem[:2] for p in NOTEBOOKS}
    for i, c in enumerate(cells):
        for ref in re.findall(r"\b[Ll]essons? (\d{1,2})\b", _source(c)):
            if numbers and f"{int(ref):02d}" not in numbers:
                problems.append(
                    f"cell {i}: 'lesson {ref}' names no notebook (numbers: {', '.join(sorted(numbers))})"
                )
        if "raises-exception" in c.get("metadata", {}).get("tags", []):
            problems.append(
                f"cell {i}: raises-exception (show a wrong answer with show_mistake instead)"
            )
        if re.search(r"<iframe|IFrame\(", _source(c)):
            problems.append(f"cell {i}: an iframe (the server is gone when the book is read)")
    return problems


def _load(path: pathlib.Path) -> dict:
    return json.loads(path.read_text(encoding="utf-8"))


CONVERTED = [p for p in NOTEBOOKS if p.stem not in PENDING]
WAITING = [p for p in NOTEBOOKS if p.stem in PENDING]


@pytest.mark.parametrize("path", CONVERTED, ids=[p.name for p in CONVERTED])
def test_lesson_shape(path):
    problems = lint(_load(path))
    assert not problems, f"{path.name}:\n  " + "\n  ".join(problems)


def test_pending_is_still_pending():
    passing = [p.name for p in WAITING if not lint(_load(p))]
    assert not passing, f"{passing} pass the lesson lint: remove them from PENDING"


def test_lint_rejects_a_bare_notebook():
    bare = {
        "cells": [
            {
                "cell_type": "markdown",
                "source": "# A lesson\n\nText, see lesson 42.",
                "metadata": {},
            }
        ]
    }
    problems = lint(bare)
    assert any("'lesson 42' names no notebook" in p for p in problems)
    assert any("Goals" in p for p in problems)
    assert any("display equations" in p for p in problems)
    assert any("Exercises" in p for p in problems)


def test_lint_accepts_the_minimal_shape():
    hidden = {
        "tags": ["hide-cell"],
        "mystnb": {"code_prompt_show": "Show the solution"},
        "jupyter": {"source_hidden": True},
    }

    def md(s):
        return {"cell_type": "markdown", "source": s, "metadata": {}}

    def code(s, meta=None):
        return {
            "cell_type": "code",
            "source": s,
            "metadata": meta or {},
            "outputs": [],
            "execution_count": None,
        }

    sol = code(f"def f():\n    {BEGIN}\n    return 1\n    ### END SOLUTION\n", hidden)
    nb = {
        "cells": [
            md("# L\n\n## Goals and prerequisites\n\nTime: 30 min"),
            md(
                "## Model\n\n$$a$$ $$b$$\n\n$$c$$\n\n| symbol | code | unit | meaning |\n|---|---|---|---|"
            ),
            md("## Your version"),
            sol,
            code("check(f)"),
            md("## Exercises"),
            sol,
            code("check(f)"),
            sol,
            code("check(f)"),
            sol,
            code("check(f)"),
            md("## Summary"),
        ]
    }
    assert lint(nb) == []
    nb["cells"][3] = code(sol["source"])  # a visible solution
    assert any("not hidden" in p for p in lint(nb))
