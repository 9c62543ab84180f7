"""Lesson 04 checkers: solutions pass, plausible mistakes are rejected with a diagnosis."""

from mutants import assert_module_checks

from orientviz.exercises import lesson04
from orientviz.exercises._common import rejection


def test_solutions_pass_and_mutants_fail():
    assert_module_checks(lesson04)


def test_diagnoses_name_the_mistake():
    m = lesson04.MUTANTS
    assert "without weights" in str(rejection(lesson04.check_resection, m["check_resection"]["weights forgotten"]))
    assert "redundancy" in str(rejection(lesson04.check_resection, m["check_resection"]["divides by n"]))
    assert "ray 1" in str(rejection(lesson04.check_two_rays, m["check_two_rays"]["point on ray 1"]))
    assert "alternate" in str(rejection(lesson04.check_design_X0, m["check_design_X0"]["rows x.. then y.."]))
    assert "√2" in str(rejection(lesson04.check_sigma_Z, m["check_sigma_Z"]["no sqrt 2"]))
    assert "weights P are missing" in str(rejection(lesson04.check_normal_step, m["check_normal_step"]["weights forgotten"]))
