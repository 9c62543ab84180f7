"""Lesson 15's checkers: solutions pass, blanks are 'not written yet', mutants fail by far."""

from answers import lesson15 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson15


def test_checks():
    assert_module_checks(lesson15, answers)


def test_diagnoses_name_the_mistake():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson15,
        answers,
        {
            ("check_smallest_redundancy", "one-sided"): "one-sided",
            ("check_smallest_redundancy", "squared"): "bound for σ̂0²",
            ("check_smallest_redundancy", "off by one"): "off by one",
        },
    )
