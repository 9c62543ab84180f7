"""Lesson 11's checkers: solutions pass, blanks are 'not written yet', mutants fail by far."""

from answers import lesson11 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson11


def test_checks():
    assert_module_checks(lesson11, answers)
