"""Lesson 09 (the datum): solutions pass, every plausible mistake is rejected by far
and named in the message."""

from __future__ import annotations

from answers import lesson09 as answers
from mutants import assert_diagnoses, assert_module_checks

from orientviz.exercises import lesson09


def test_lesson09_checks():
    assert_module_checks(lesson09, answers)


def test_lesson09_diagnoses_name_the_mistake():
    assert_diagnoses(
        lesson09,
        answers,
        {
            ("check_inner_solve", "ridge"): "regularises",
            ("check_inner_solve", "whole_inverse"): "whole bordered inverse",
            ("check_inner_solve", "sign"): "sign of dx",
            ("check_helmert_columns", "rotation_yx"): "(−y, x)",
            ("check_helmert_columns", "scale_for_rotation"): "change of scale",
            ("check_helmert_columns", "no_translations"): "two shifts and one rotation",
            ("check_s_transform", "all_points"): "datum points are only",
            ("check_s_transform", "no_St"): "not S Q",
            ("check_s_transform", "Q_unchanged"): "Q must be transformed",
            ("check_distance_std", "diag"): "only the diagonal",
            ("check_distance_std", "blocks"): "only their 2×2 blocks",
            ("check_distance_std", "variance"): "square root",
            ("check_null_space", "relative tolerance"): "too large",
            ("check_null_space", "largest jump"): "largest jump",
            ("check_null_space", "absolute tolerance"): "round-off",
            ("check_null_space", "rows"): "columns are the basis vectors",
            ("check_null_space", "largest"): "LARGEST",
        },
    )
