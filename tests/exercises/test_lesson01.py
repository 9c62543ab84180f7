"""Lesson 01's checkers pass the solutions and reject every plausible wrong answer."""

from __future__ import annotations

import pytest

from orientviz.exercises import lesson01 as lesson

CASES = [(c, m) for c, ms in lesson.MUTANTS.items() for m in ms]


@pytest.mark.parametrize("check", sorted(lesson.SOLUTIONS))
def test_solution_passes(check, capsys):
    getattr(lesson, check)(lesson.SOLUTIONS[check])
    assert "✓" in capsys.readouterr().out


@pytest.mark.parametrize(("check", "mutant"), CASES)
def test_mutant_rejected(check, mutant):
    with pytest.raises(AssertionError) as err:
        getattr(lesson, check)(lesson.MUTANTS[check][mutant])
    assert "not written yet" not in str(err.value)


@pytest.mark.parametrize("check", sorted(lesson.SOLUTIONS))
def test_blank_is_not_written_yet(check):
    def blank(*args):
        raise NotImplementedError

    with pytest.raises(AssertionError, match="not written yet"):
        getattr(lesson, check)(blank)


def test_every_checker_has_mutants():
    checks = {n for n in dir(lesson) if n.startswith("check_")}
    assert checks == set(lesson.SOLUTIONS) == set(lesson.MUTANTS)
    assert all(len(m) >= 2 for m in lesson.MUTANTS.values())
