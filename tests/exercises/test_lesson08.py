"""Lesson 08's checkers: solutions pass, blanks are 'not written yet', mutants fail by far."""

from answers import lesson08 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson08


def test_checks():
    assert_module_checks(lesson08, answers)


def test_diagnoses_name_the_mistake():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson08,
        answers,
        {
            ("check_compose", "order"): "order is wrong",
            ("check_compose", "no scale in t"): "scale m1 is missing",
            ("check_compose", "no rotation in t"): "rotation R1 is missing",
            ("check_intersect_many", "R transposed"): "R transposed",
            ("check_conformal", "conjugate pairing"): "x − iy",
            ("check_conformal", "no constant"): "c0 (the shift) is missing",
            ("check_strips_for", "natural log"): "natural logarithm",
            ("check_strips_for", "a forgotten"): "a is missing",
            ("check_strips_for", "exponent only"): "log10 n_s, not n_s",
            ("check_strips_for", "b <= 0 not handled"): "never rises",
            ("check_intersect_many", "+c"): "z = −c",
            ("check_determined", "counting"): "seven known coordinates are not enough",
            ("check_determined", "two heights"): "three points with Z",
            ("check_determined", "plan points ignored"): "planimetric points",
            ("check_determined", "one plan point"): "two points with X, Y",
            ("check_intersect_many", "not normalised"): "not normalised",
            ("check_intersect_many", "pairwise midpoints"): "pairwise midpoints",
        },
    )
