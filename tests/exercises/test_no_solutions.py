"""Solutions stay with the teacher: the installed checker modules hold no solution.

The solutions and the plausible wrong answers of every exercise live here in the tests
(``answers/lessonNN.py``) and in the lesson notebooks between the ``### BEGIN SOLUTION``
markers, which the student release (``tools/make_student_release.py``) blanks. What the
package ships is only the checks: no ``SOLUTIONS``/``MUTANTS`` tables, and no function of a
checker module that a check accepts when it is handed in as the answer.
"""

from __future__ import annotations

import contextlib
import importlib
import inspect
import io
import pathlib
import warnings

import pytest

import orientviz.exercises as exercises

PACKAGE = pathlib.Path(exercises.__file__).parent
MODULES = sorted(p.stem for p in PACKAGE.glob("lesson[0-9][0-9].py"))


#: Oracles that compute the right answer by another method than the one the lesson asks for
#: (brute force, numerical derivatives, leave-one-out, Rodrigues rotations, numpy's lstsq);
#: handed in, they pass — as any correct oracle would — but they are not the lesson's method.
INDEPENDENT_ORACLES = {
    "lesson01": {
        "_second_difference_exact": "a second difference in 50-digit decimal arithmetic, not the "
        "derived closed form (a student who does that has left floating point on purpose)"
    },
    "lesson02": {"_rodrigues_opk": "three Rodrigues rotations, not the written-out R_ω R_φ R_κ"},
    "lesson04": {"_numeric_design": "central differences of the collinearity equations"},
    "lesson07": {"_numeric_design": "central differences of the similarity"},
    "lesson12": {"_oracle_w": "redundancy numbers by leave-one-out, not from Q_vv P"},
    "lesson16": {"_worst_after": "the inverse of the enlarged N, not the update formula"},
}


def _passes(check, candidate) -> bool:
    out = io.StringIO()
    with contextlib.redirect_stdout(out), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            check(candidate)
        except Exception:  # a wrong answer, a wrong signature: not a solution
            return False
    return out.getvalue().startswith("✓")


def test_every_lesson_has_a_checker_module():
    assert len(MODULES) == 17


@pytest.mark.parametrize("name", MODULES)
def test_no_solution_table_and_no_function_passes_a_check(name):
    module = importlib.import_module(f"orientviz.exercises.{name}")
    assert not hasattr(module, "SOLUTIONS") and not hasattr(module, "MUTANTS")
    checks = {k: v for k, v in vars(module).items() if k.startswith("check_") and callable(v)}
    assert checks, f"{name}: no checks"
    own = [
        v
        for k, v in vars(module).items()
        if inspect.isfunction(v)
        and v.__module__ == module.__name__
        and not k.startswith("check_")
        and k not in INDEPENDENT_ORACLES.get(name, {})
    ]
    passing = [
        f"{check_name} accepts {f.__name__}"
        for check_name, check in checks.items()
        for f in own
        if _passes(check, f)
    ]
    assert not passing, f"{name} ships a solution: {passing}"


def test_the_independent_oracles_exist():
    for name, oracles in INDEPENDENT_ORACLES.items():
        module = importlib.import_module(f"orientviz.exercises.{name}")
        for oracle in oracles:
            assert inspect.isfunction(getattr(module, oracle)), f"{name}.{oracle}"


def _solution_blocks() -> list[tuple[str, list[str]]]:
    """(notebook, normalised non-trivial lines) of every solution block in the lessons."""
    import json

    root = pathlib.Path(__file__).parents[2]
    blocks = []
    for path in sorted((root / "notebooks").glob("*.ipynb")):
        for cell in json.loads(path.read_text(encoding="utf-8"))["cells"]:
            src = cell["source"]
            text = "".join(src) if isinstance(src, list) else src
            inside, body = False, []
            for line in text.splitlines():
                s = line.strip()
                if s == "### BEGIN SOLUTION":
                    inside, body = True, []
                elif s == "### END SOLUTION":
                    inside = False
                    if len(body) >= 3:
                        blocks.append((path.name, body))
                elif inside and s and not s.startswith("#"):
                    body.append("".join(s.split()))
    return blocks


def test_no_solution_block_is_in_the_installed_sources():
    """No three consecutive statements of a lesson's solution appear in the checkers' sources.

    The wheel packs src/orientviz only (tools/, tests/ and notebooks/ are not in it). The
    library itself implements the methods the lessons teach (the student's version is
    compared with it), so the search covers the exercises package, where the checks live."""
    blocks = _solution_blocks()
    assert len(blocks) > 30
    files = {}
    for f in PACKAGE.rglob("*.py"):
        lines = ["".join(s.split()) for s in f.read_text(encoding="utf-8").splitlines()]
        lines = [s for s in lines if s and not s.startswith("#")]
        files[f] = set(zip(lines, lines[1:], lines[2:]))
    found = [
        f"{nb}: {' / '.join(triple)} in {f.relative_to(PACKAGE)}"
        for nb, body in blocks
        for triple in zip(body, body[1:], body[2:])
        for f, triples in files.items()
        if triple in triples
    ]
    assert not found, found[:5]
