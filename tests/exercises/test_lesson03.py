"""Lesson 03 (DLT and interior orientation): solutions pass, every plausible mistake is rejected by far
and named in the message."""

from __future__ import annotations

from answers import lesson03 as answers
from mutants import assert_diagnoses, assert_module_checks

from orientviz.exercises import lesson03


def test_lesson03_checks():
    assert_module_checks(lesson03, answers)


def test_lesson03_diagnoses_name_the_mistake():
    assert_diagnoses(
        lesson03,
        answers,
        {
            ("check_affine_fit", "interleaved"): "the order is",
            ("check_affine_fit", "r_2n"): "not 2n.",
            ("check_affine_fit", "r_2n_3"): "not 2n − 3",
            ("check_affine_fit", "v_sign"): "sign of v",
            ("check_shift_origin", "no rescale"): "not scaled back",
            ("check_shift_origin", "last column"): "only the last column",
            ("check_shift_origin", "sign"): "wrong way",
            ("check_viewing_direction", "m3 as it is"): "sign of λ is missing",
            ("check_viewing_direction", "minus m3"): "sign of λ is missing",
            ("check_viewing_direction", "reversed"): "from the scene to the camera",
            ("check_interior_from_dlt", "unnormalised"): "division by |m3|²",
            ("check_interior_from_dlt", "no_x0"): "subtract x0²",
            ("check_interior_from_dlt", "swapped"): "swapped",
        },
    )
