"""Docstrings the book's API pages can render: no stray RST substitution references.

Sphinx reads ``|x|`` in a docstring as a substitution reference and warns (the book build
then fails, tests/book). Write a norm or an absolute value as ``‖x‖``, as a literal
(````|x|````) or inside a ``:math:`` role.
"""

import ast
import pathlib
import re

import orientviz

SRC = pathlib.Path(orientviz.__file__).parent
#: a '|' that opens an inline markup start-string: not after a word character, a backquote, a
#: backslash or another '|', and followed by a non-space character (RST's inline markup rule)
START = re.compile(r"(?<![\w`|\\])\|(?=[^\s|])")
#: literals and math roles, where '|' is plain text
QUOTED = re.compile(r"``.*?``|:math:`[^`]*`")


def stray_bars(text: str) -> list[str]:
    """Lines of ``text`` with a '|' that RST would read as a substitution start."""
    return [line.strip() for line in text.splitlines() if START.search(QUOTED.sub("", line))]


def test_the_rule_finds_a_bare_absolute_value_and_passes_the_quoted_ones():
    assert stray_bars("the largest |w| of a ray")
    assert stray_bars("The minimum of |o + s·d|² over s")
    assert not stray_bars("the largest ``|w|`` of a ray, :math:`|v|`, ‖x‖, a | b table")


def test_no_docstring_in_src_has_a_stray_substitution_reference():
    found = []
    for path in sorted(SRC.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
                doc = ast.get_docstring(node, clean=False)
                for line in stray_bars(doc or ""):
                    name = getattr(node, "name", "module")
                    found.append(f"{path.relative_to(SRC)}: {name}: {line[:80]}")
    assert not found, "write ‖x‖ or ``|x|``:\n" + "\n".join(found)
