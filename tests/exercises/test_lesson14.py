"""Lesson 14's checkers: solutions pass, blanks are 'not written yet', mutants fail by far."""

from answers import lesson14 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson14


def test_checks():
    assert_module_checks(lesson14, answers)
