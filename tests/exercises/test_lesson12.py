"""Lesson 12's checkers: solutions pass, blanks are 'not written yet', mutants fail by far."""

from answers import lesson12 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson12


def test_checks():
    assert_module_checks(lesson12, answers)


def test_diagnoses_name_the_mistake():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson12,
        answers,
        {
            ("check_snoop", "all at once"): "one at a time",
            ("check_snoop", "no abs"): "not w",
            ("check_snoop", "one round"): "go on until",
            ("check_snoop_round", "signed"): "test |w|",
            ("check_external", "N not inverted"): "multiplied by AᵀA",
            ("check_external", "unweighted"): "weights were forgotten",
            ("check_external", "sign"): "opposite sign",
        },
    )
