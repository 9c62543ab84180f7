"""Lesson 11's checkers: solutions pass, blanks are 'not written yet', mutants fail by far."""

from answers import lesson11 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson11


def test_checks():
    assert_module_checks(lesson11, answers)


def test_diagnoses_name_the_mistake():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson11,
        answers,
        {
            ("check_inflation", "variance"): "ratio of the VARIANCES",
            ("check_inflation", "inverted"): "cannot make the first more precise",
            ("check_inflation", "rho"): "ρ itself",
            ("check_inflation", "abs rho"): "ρ enters squared",
            ("check_significant", "signed"): "the sign was kept",
            ("check_described_share", "remainder"): "remainder's share",
        },
    )
