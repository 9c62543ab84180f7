"""Lesson 04 checkers: solutions pass, plausible mistakes are rejected with a diagnosis."""

from answers import lesson04 as answers
from mutants import assert_diagnoses, assert_module_checks

from orientviz.exercises import lesson04


def test_solutions_pass_and_mutants_fail():
    assert_module_checks(lesson04, answers)


def test_diagnoses_name_the_mistake():
    assert_diagnoses(
        lesson04,
        answers,
        {
            ("check_resection", "weights forgotten"): "without weights",
            ("check_rho_x0_phi", "N"): "normal matrix N",
            ("check_rho_x0_phi", "sign of ∂x/∂X0"): "one column of the design has the wrong sign",
            ("check_design_X0", "the stand-in (numeric_X0)"): "calls the library's project",
            ("check_rho_x0_phi", "cofactor"): "not divided by",
            ("check_rho_x0_phi", "x only"): "only the x equations",
            ("check_resection", "divides by n"): "redundancy",
            ("check_resection", "one iteration"): "after 1 Gauss-Newton step",
            ("check_resection", "two iterations"): "after 2 Gauss-Newton steps",
            ("check_resection", "no iteration"): "the start itself",
            ("check_two_rays", "point on ray 1"): "ray 1",
            ("check_design_X0", "rows x.. then y.."): "alternate",
            ("check_sigma_X", "midway"): "midway",
            ("check_sigma_X", "independent"): "independent",
            ("check_sigma_X", "one image"): "left image alone",
            ("check_sigma_X", "sum"): "instead of their squares",
            ("check_sigma_X", "micrometres"): "not µm",
            ("check_two_rays", "sign of the cross term"): "cross term",
            ("check_best_extra_point", "farthest from the centre"): "farthest",
            ("check_best_extra_point", "weights forgotten"): "forgotten weight",
            ("check_best_extra_point", "always Y0"): "not for X0",
            ("check_best_extra_point", "argmax"): "worst",
        },
    )
