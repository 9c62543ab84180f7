"""Lesson 02 checkers: solutions pass, plausible mistakes are rejected with a diagnosis."""

from answers import lesson02 as answers
from mutants import assert_diagnoses, assert_module_checks

from orientviz.exercises import lesson02


def test_solutions_pass_and_mutants_fail():
    assert_module_checks(lesson02, answers)


def test_oracle_agrees_with_the_library():
    """The checker's Rodrigues oracle and the library are independent; they must agree."""
    import numpy as np

    from orientviz.rotation import matrix_from_opk

    a = np.array([12.0, -31.0, 57.0])
    assert np.allclose(lesson02._rodrigues_opk(*a), matrix_from_opk(*(a * np.pi / 200)), atol=1e-12)


def test_widget_names_the_locked_pair_of_its_sequence():
    """Gimbal lock couples the primary angle with κ: ω ± κ in ω-φ-κ, φ ± κ in φ-ω-κ."""
    from orientviz.widgets.rotation import describe, rotation_state

    assert "only ω ± κ" in describe(rotation_state(0.0, 100.0, 30.0))
    assert "only φ ± κ" in describe(rotation_state(100.0, 30.0, 0.0, sequence="pok"))


def test_diagnoses_name_the_mistake():
    assert_diagnoses(
        lesson02,
        answers,
        {
            ("check_rotation", "transpose"): "transpose",
            ("check_opk_from_matrix", "transpose"): "angles of Rᵀ",
            ("check_rotation", "degrees"): "degrees",
            ("check_rotation", "phi-omega-kappa order"): "φ-ω-κ",
            ("check_collinearity", "R instead of R^T"): "Rᵀ",
            ("check_gimbal_pok", "kappa forgotten"): "same axis",
            ("check_gimbal_pok", "the opk rule"): "ω-φ-κ rule",
            ("check_opk_from_matrix", "degrees"): "degrees instead of gon",
            ("check_vertical_partials", "all signs"): "every sign is reversed",
            ("check_opk_from_matrix", "arctan"): "arctan loses the quadrant",
            ("check_vertical_partials", "own central differences"): "finite difference",
            ("check_vertical_partials", "1 forgotten"): "the 1 in c(1 + x²/c²)",
            ("check_vertical_partials", "omega phi swapped"): "ω and φ columns are swapped",
            ("check_vertical_partials", "kappa sign"): "κ column has the wrong sign",
            ("check_vertical_partials", "per gon"): "per gon, not per radian",
            ("check_vertical_partials", "rows swapped"): "rows) are swapped",
            ("check_relief_displacement", "foot's factor"): "h/(H − h) goes with the foot",
            ("check_relief_displacement", "sign"): "sign is reversed",
        },
    )
