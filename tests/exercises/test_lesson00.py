"""Lesson 00 checkers: solutions pass, plausible mistakes are rejected with a diagnosis."""

from mutants import assert_module_checks

from orientviz.exercises import lesson00
from orientviz.exercises._common import rejection


def test_solutions_pass_and_mutants_fail():
    assert_module_checks(lesson00)


def test_diagnoses_name_the_mistake():
    m = lesson00.MUTANTS
    assert "weights are missing" in str(rejection(lesson00.check_sigma0, m["check_sigma0"]["no weights"]))
    assert "redundancy r" in str(rejection(lesson00.check_sigma0, m["check_sigma0"]["divides by n"]))
    assert "two observations" in str(rejection(lesson00.check_redundancy, m["check_redundancy"]["one observation per ray"]))
    assert "one-sided" in str(rejection(lesson00.check_critical_value, m["check_critical_value"]["one-sided"]))
    assert "need the weights" in str(rejection(lesson00.check_normalized, m["check_normalized"]["unweighted r"]))
