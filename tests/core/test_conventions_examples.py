"""The worked examples of docs/conventions.md ("From your textbook to orientviz") run.

Their code blocks hold the checks (asserts); they run in one namespace, in order.
"""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_textbook_examples_round_trip():
    text = (ROOT / "docs" / "conventions.md").read_text(encoding="utf-8")
    section = text.split("## From your textbook to orientviz", 1)[1]
    blocks = re.findall(r"```python\n(.*?)```", section, re.S)
    assert len(blocks) == 4
    namespace: dict = {}
    printed = []
    for code in blocks:
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            exec(compile(code, "docs/conventions.md", "exec"), namespace)  # noqa: S102
        printed.append(out.getvalue())
    assert namespace["adj"].redundancy > 0 and "R_book" in namespace and "book_xy" in namespace
    # Example 4: the three estimators ran, and the page shows what its code prints
    assert set(namespace["result"]) == {"parallax", "collinearity", "coplanarity"}
    shown = re.findall(r"```text\n(.*?)```", section.split("**Example 4", 1)[1], re.S)
    assert shown == [printed[3]]


def test_the_table_names_the_five_textbooks():
    section = (ROOT / "docs" / "conventions.md").read_text(encoding="utf-8")
    table = section.split("## From your textbook to orientviz", 1)[1].split("\n\n")[2]
    for author in ("Wolf", "Mikhail", "McGlone", "Kraus", "Luhmann"):
        assert author in table
