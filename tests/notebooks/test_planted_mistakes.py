"""Every planted mistake of the lessons ("a colleague's version: one line is wrong") is wrong.

An exercise of the kind "find the mistake" shows a colleague's function with one wrong line
and asks the student for the corrected one. This test executes each such cell of the lesson
notebooks and demands that the exercise's checker rejects the colleague's function with a
diagnosis (a :class:`~orientviz.exercises.CheckFailed` that names a mistake), so that no
planted "mistake" is in fact right and no checker lets it through.
"""

from __future__ import annotations

import contextlib
import importlib
import io
import json
import pathlib
import re

import numpy as np
import pytest
from scipy.stats import norm

from orientviz.exercises import CheckFailed
from orientviz.orientation.relative import design_dependent

ROOT = pathlib.Path(__file__).parents[2]


def rejection(check, answer):
    """The CheckFailed that ``check(answer)`` raises (None if it passes), its ✓ line silenced."""
    with contextlib.redirect_stdout(io.StringIO()):
        try:
            check(answer)
        except CheckFailed as exc:
            return exc
    return None


MARK = "# A colleague's version: one line is wrong."

#: (lesson, function) → (checker, a piece of its diagnosis)
CHECKERS = {
    ("10", "point_covariance"): ("check_point_covariance", "ADDS to the point's"),
    ("14", "ppi_image"): ("check_ppi_image", "true horizontal distance"),
}


def _planted() -> list[tuple[str, str, str]]:
    out = []
    for path in sorted((ROOT / "notebooks").glob("*.ipynb")):
        for cell in json.loads(path.read_text(encoding="utf-8"))["cells"]:
            src = "".join(cell["source"])
            if cell["cell_type"] == "code" and src.startswith(MARK):
                name = re.search(r"^def (\w+)_colleague\(", src, re.M).group(1)
                out.append((path.name[:2], name, src))
    return out


PLANTED = _planted()


def test_every_planted_mistake_is_listed():
    assert {(les, name) for les, name, _ in PLANTED} == set(CHECKERS)


@pytest.mark.parametrize("lesson,name,src", PLANTED, ids=[f"{a}-{b}" for a, b, _ in PLANTED])
def test_the_planted_mistake_is_rejected_and_named(lesson, name, src):
    namespace = {"np": np, "norm": norm, "design_dependent": design_dependent}
    exec(
        compile(src, f"lesson {lesson}: {name}_colleague", "exec"), namespace
    )  # the lesson's own cell
    checker, diagnosis = CHECKERS[(lesson, name)]
    module = importlib.import_module(f"orientviz.exercises.lesson{lesson}")
    exc = rejection(getattr(module, checker), namespace[f"{name}_colleague"])
    assert exc is not None, f"lesson {lesson}: the colleague's {name} passes its check"
    assert diagnosis in str(exc), f"lesson {lesson}: {name}: expected {diagnosis!r} in {exc}"
