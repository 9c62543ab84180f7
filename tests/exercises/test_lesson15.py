"""Lesson 15's checkers: solutions pass, blanks are 'not written yet', mutants fail by far."""

from answers import lesson15 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson15


def test_checks():
    assert_module_checks(lesson15, answers)
