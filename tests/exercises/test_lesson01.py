"""Lesson 01 (least squares): solutions pass, every plausible mistake is rejected by far
and named in the message."""

from __future__ import annotations

from answers import lesson01 as answers
from mutants import assert_diagnoses, assert_module_checks

from orientviz.exercises import lesson01


def test_lesson01_checks():
    assert_module_checks(lesson01, answers)


def test_lesson01_diagnoses_name_the_mistake():
    assert_diagnoses(
        lesson01,
        answers,
        {
            ("check_line_fit", "no_weights"): "weights are forgotten",
            ("check_line_fit", "one_over_sigma"): "1/σ instead of 1/σ²",
            ("check_line_fit", "divide_by_n"): "redundancy r = n − 2",
            ("check_line_fit", "Q_is_N"): "inverse of N",
            ("check_line_fit", "v_sign"): "sign of v",
            ("check_mean_sigma", "variance"): "square root",
            ("check_mean_sigma", "mean sigma"): "only for equal σ",
            ("check_mean_sigma", "one over sigma"): "weights 1/σ",
            ("check_weakest_direction", "strong"): "BEST-determined",
            ("check_weakest_direction", "unweighted"): "σ are missing",
            ("check_second_order", "whole dx"): "ACROSS the ray",
            ("check_second_order", "no half"): "factor 1/2",
            ("check_second_order", "along"): "ALONG the ray",
            ("check_second_order", "sign"): "convex",
            ("check_second_order", "exact"): "whole linearisation error",
            ("check_second_order", "second difference, t 0.001"): "finite difference",
            ("check_group_sigma0", "n_g"): "number of observations",
            ("check_group_sigma0", "share"): "in proportion to the group's size",
            ("check_group_sigma0", "no_weights"): "weights are missing",
            ("check_group_sigma0", "squared"): "σ̂0², not σ̂0",
        },
    )
