"""Lesson 07 checkers: solutions pass, plausible mistakes are rejected with a diagnosis."""

import numpy as np
from answers import lesson07 as answers
from mutants import assert_diagnoses, assert_module_checks

from orientviz.exercises import lesson07


def test_solutions_pass_and_mutants_fail():
    assert_module_checks(lesson07, answers)


def test_oracle_design_agrees_with_the_closed_form_solution():
    """The numerical design matrix (oracle) and the hand-written one agree (both independent of the library)."""
    rng = np.random.default_rng(0)
    x, mm, R, _ = lesson07._model(rng, 3)
    assert np.allclose(
        lesson07._numeric_design(x, mm, R), answers._sol_design(x, mm, R), rtol=1e-6, atol=1e-6
    )


def test_diagnoses_name_the_mistake():
    assert_diagnoses(
        lesson07,
        answers,
        {
            (
                "check_similarity_gn",
                "r_nobs",
            ): "the redundancy is the number of control coordinates",
            ("check_similarity_gn", "no_sqrt"): "square root is missing",
            ("check_similarity_gn", "no_weights"): "weights are missing",
            ("check_similarity_gn", "one_step"): "iterate until",
            ("check_similarity", "transpose"): "Rᵀ",
            ("check_similarity", "no reflection fix"): "det",
            ("check_similarity", "symmetric scale"): "symmetric scale",
            ("check_similarity", "T without scale"): "scale m is missing",
            ("check_free_axis", "normal"): "perpendicular to the line",
            ("check_free_axis", "centroid"): "origin plays no part",
            ("check_free_axis", "not unit"): "UNIT vector",
            ("check_design", "model axes"): "MODEL axes",
            ("check_design", "sign of the rotation columns"): "wrong sign",
            ("check_design", "scale column times m"): "without m",
        },
    )


def test_similarity_gn_names_the_rotation_update_on_the_wrong_side():
    """R ← R R(α) instead of R(α) R converges slowly to nearly the same point (R off by ~1e-6,
    so it is not among the MUTANTS, which must miss by 100× the tolerance); the check still
    rejects it and names it from a one-step probe."""
    from orientviz.exercises import rejection

    exc = rejection(
        lesson07.check_similarity_gn,
        lambda *a: answers._similarity_gn(*a, mistake="right_side"),
    )
    assert exc is not None and "wrong side" in str(exc), exc
    exc = rejection(
        lesson07.check_similarity_gn,
        lambda *a: answers._similarity_gn(*a, mistake="one_step"),
    )
    assert "wrong side" not in str(exc)
