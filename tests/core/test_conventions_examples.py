"""The worked examples of docs/conventions.md ("From your textbook to orientviz") run.

Their code blocks hold the checks (asserts); they run in one namespace, in order.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_textbook_examples_round_trip():
    text = (ROOT / "docs" / "conventions.md").read_text(encoding="utf-8")
    section = text.split("## From your textbook to orientviz", 1)[1]
    blocks = re.findall(r"```python\n(.*?)```", section, re.S)
    assert len(blocks) == 3
    namespace: dict = {}
    for code in blocks:
        exec(compile(code, "docs/conventions.md", "exec"), namespace)  # noqa: S102
    assert namespace["adj"].redundancy > 0 and "R_book" in namespace and "book_xy" in namespace


def test_the_table_names_the_five_textbooks():
    section = (ROOT / "docs" / "conventions.md").read_text(encoding="utf-8")
    table = section.split("## From your textbook to orientviz", 1)[1].split("\n\n")[2]
    for author in ("Wolf", "Mikhail", "McGlone", "Kraus", "Luhmann"):
        assert author in table
