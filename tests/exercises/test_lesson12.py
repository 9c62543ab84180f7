"""Lesson 12's checkers: solutions pass, blanks are 'not written yet', mutants fail by far."""

from answers import lesson12 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson12


def test_checks():
    assert_module_checks(lesson12, answers)
