"""Lesson 13's checkers: solutions pass, blanks are 'not written yet', mutants fail by far."""

from answers import lesson13 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson13


def test_checks():
    assert_module_checks(lesson13, answers)


def test_diagnoses_name_the_mistake():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson13,
        answers,
        {
            ("check_gnss_rows", "minus offset"): "wrong sign",
            ("check_gnss_rows", "wrong strip"): "another strip",
            ("check_gnss_rows", "drift 1"): "holds 1",
            ("check_difference_covariance", "independent"): "not independent",
            ("check_from_differences", "independent"): "taken as independent",
            ("check_from_differences", "C as weight"): "covariance itself used as the weight",
            ("check_from_differences", "no offset"): "without the offset",
            ("check_from_differences", "the offset model again"): "is the offset model again",
        },
    )


def test_the_lessons_stand_in_is_refused_and_named():
    from mutants import assert_diagnoses

    for text in ["calls the library's statoscope_row_library", "stand-in"]:
        assert_diagnoses(lesson13, answers, {("check_statoscope_row", "the stand-in"): text})
