"""Lesson 02 checkers: solutions pass, plausible mistakes are rejected with a diagnosis."""

from mutants import assert_module_checks

from orientviz.exercises import lesson02
from orientviz.exercises._common import rejection


def test_solutions_pass_and_mutants_fail():
    assert_module_checks(lesson02)


def test_diagnoses_name_the_mistake():
    m = lesson02.MUTANTS
    assert "transpose" in str(rejection(lesson02.check_rotation, m["check_rotation"]["transpose"]))
    assert "degrees" in str(rejection(lesson02.check_rotation, m["check_rotation"]["degrees"]))
    assert "φ-ω-κ" in str(rejection(lesson02.check_rotation, m["check_rotation"]["phi-omega-kappa order"]))
    assert "Rᵀ" in str(rejection(lesson02.check_collinearity, m["check_collinearity"]["R instead of R^T"]))
    assert "same axis" in str(rejection(lesson02.check_gimbal, m["check_gimbal"]["kappa forgotten"]))
    assert "degrees instead of gon" in str(rejection(lesson02.check_opk_from_matrix, m["check_opk_from_matrix"]["degrees"]))


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
