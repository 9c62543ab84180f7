"""Lesson 05 checkers: solutions pass, plausible mistakes are rejected with a diagnosis."""

import numpy as np
from mutants import assert_module_checks

from orientviz.exercises import lesson05
from orientviz.exercises._common import rejection


def test_solutions_pass_and_mutants_fail():
    assert_module_checks(lesson05)


def test_diagnoses_name_the_mistake():
    m = lesson05.MUTANTS
    assert "opposite sign" in str(rejection(lesson05.check_design, m["check_design"]["y'' - y'"]))
    assert "Kovarik" in str(rejection(lesson05.check_design, m["check_design"]["Kovarik signs"]))
    assert "degrees" in str(rejection(lesson05.check_six_point, m["check_six_point"]["degrees"]))
    assert "swapped" in str(rejection(lesson05.check_six_point, m["check_six_point"]["phi and kappa swapped"]))
    assert "scale it to the model" in str(rejection(lesson05.check_parallax, m["check_parallax"]["image difference"]))


def test_oracle_agrees_with_the_library():
    """The checker's rigorous-parallax derivatives and the library's design matrix are independent; they agree."""
    from orientviz.orientation.relative import design_dependent

    P = lesson05._points(np.random.default_rng(3), 9, 92.0)
    assert np.allclose(lesson05._numeric_design(P, 92.0), design_dependent(P[:, 0], P[:, 1], P[:, 2], 92.0), rtol=1e-5, atol=1e-6)


def test_condition_and_precision_diagnoses():
    m = lesson05.MUTANTS
    assert "flat-terrain form" in str(rejection(lesson05.check_condition, m["check_condition"]["flat form with relief"]))
    assert "diagonal of (AᵀA)⁻¹" in str(rejection(lesson05.check_scheme_sigma, m["check_scheme_sigma"]["inverse of the diagonal"]))
