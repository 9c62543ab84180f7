"""Lesson 13's checkers: solutions pass, blanks are 'not written yet', mutants fail by far."""

from answers import lesson13 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson13


def test_checks():
    assert_module_checks(lesson13, answers)
