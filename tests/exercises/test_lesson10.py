"""Lesson 10 (sparse normal equations): solutions pass, every plausible mistake is rejected by far
and named in the message."""

from __future__ import annotations

from answers import lesson10 as answers
from mutants import assert_diagnoses, assert_module_checks

from orientviz.exercises import lesson10


def test_lesson10_checks():
    assert_module_checks(lesson10, answers)


def test_lesson10_diagnoses_name_the_mistake():
    assert_diagnoses(
        lesson10,
        answers,
        {
            ("check_schur_step", "plus"): "sign is wrong",
            ("check_ray_partials", "R_not_transposed"): "instead of Rᵀ",
            ("check_ray_partials", "no_quotient"): "quotient rule",
            ("check_ray_partials", "X0_sign"): "X0 enters as X − X0",
            ("check_my_bundle", "fixed_as_unknowns"): "held fixed (control) are no unknowns",
            ("check_my_bundle", "no_sqrt"): "square root is missing",
            ("check_point_covariance", "V_only"): "uncertainty of the orientations",
            ("check_schur_step", "no_coupling"): "coupling",
            ("check_schur_step", "W_transposed"): "is a matrix transposed",
            ("check_reduce", "plus"): "sign is wrong",
            ("check_reduce", "rhs_not_reduced"): "right side is reduced too",
            ("check_reduce", "no_inverse"): "V must be inverted",
            ("check_back_substitute", "no_coupling"): "coupling Wᵀ dc is missing",
            ("check_back_substitute", "plus"): "sign of Wᵀ dc",
            ("check_back_substitute", "no_inverse"): "multiplies instead",
            ("check_bandwidth", "full"): "full width",
            ("check_bandwidth", "with_diagonal"): "diagonal is not counted",
            ("check_bandwidth", "row_count"): "zeros inside the band",
        },
    )
