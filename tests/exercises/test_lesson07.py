"""Lesson 07 checkers: solutions pass, plausible mistakes are rejected with a diagnosis."""

import numpy as np
from mutants import assert_module_checks

from orientviz.exercises import lesson07
from orientviz.exercises._common import rejection


def test_solutions_pass_and_mutants_fail():
    assert_module_checks(lesson07)


def test_diagnoses_name_the_mistake():
    m = lesson07.MUTANTS
    assert "Rᵀ" in str(rejection(lesson07.check_similarity, m["check_similarity"]["transpose"]))
    assert "det" in str(rejection(lesson07.check_similarity, m["check_similarity"]["no reflection fix"]))
    assert "symmetric scale" in str(rejection(lesson07.check_similarity, m["check_similarity"]["symmetric scale"]))
    assert "scale m is missing" in str(rejection(lesson07.check_similarity, m["check_similarity"]["T without scale"]))
    assert "centre" in str(rejection(lesson07.check_sigma_scale, m["check_sigma_scale"]["not centred"]))
    assert "wrong sign" in str(rejection(lesson07.check_design, m["check_design"]["sign of the rotation columns"]))


def test_oracle_design_agrees_with_the_closed_form_solution():
    """The numerical design matrix (oracle) and the hand-written one agree (both independent of the library)."""
    rng = np.random.default_rng(0)
    x, mm, R, _ = lesson07._model(rng, 3)
    assert np.allclose(lesson07._numeric_design(x, mm, R), lesson07._sol_design(x, mm, R), rtol=1e-6, atol=1e-6)
