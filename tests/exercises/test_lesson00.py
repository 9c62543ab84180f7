"""Lesson 00 checkers: solutions pass, plausible mistakes are rejected with a diagnosis."""

from answers import lesson00 as answers
from mutants import assert_diagnoses, assert_module_checks

from orientviz.exercises import lesson00


def test_solutions_pass_and_mutants_fail():
    assert_module_checks(lesson00, answers)


def test_diagnoses_name_the_mistake():
    assert_diagnoses(
        lesson00,
        answers,
        {
            ("check_sigma0", "no weights"): "weights are missing",
            ("check_sigma0", "divides by n"): "redundancy r",
            ("check_redundancy", "one observation per ray"): "two observations",
            ("check_redundancy", "weighted: unknowns only"): "the unknowns alone",
            ("check_redundancy", "weighted: observations only"): "but also 3 unknowns",
            ("check_flagged_clean", "one-sided"): "one tail only",
            ("check_flagged_clean", "one observation"): "ONE observation",
            ("check_flagged_clean", "at least one"): "at least one",
            ("check_after_doubling", "sigma0 doubled"): "halve it",
            ("check_after_doubling", "r halved"): "relative weights only",
            ("check_after_doubling", "w unchanged"): "so w halves",
        },
    )
