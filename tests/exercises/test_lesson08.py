"""Lesson 08's checkers: solutions pass, blanks are 'not written yet', mutants fail by far."""

from answers import lesson08 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson08


def test_checks():
    assert_module_checks(lesson08, answers)
