"""Lesson 06 (epipolar geometry): solutions pass, every plausible mistake is rejected by far
and named in the message."""

from __future__ import annotations

from answers import lesson06 as answers
from mutants import assert_diagnoses, assert_module_checks

from orientviz.exercises import lesson06


def test_lesson06_checks():
    assert_module_checks(lesson06, answers)


def test_lesson06_diagnoses_name_the_mistake():
    assert_diagnoses(
        lesson06,
        answers,
        {
            ("check_eight_point", "no_rank2"): "rank 3",
            ("check_eight_point", "not_scaled"): "not scaled",
            ("check_eight_point", "transposed"): "E is transposed",
            ("check_plane_points", "counting"): "counting points is not enough",
            ("check_plane_points", "plane useless"): "points on a plane do help",
            ("check_plane_points", "seven"): "not seven",
            ("check_epipole", "left"): "LEFT epipole",
            ("check_epipole", "sign"): "sign is reversed",
            ("check_epipole", "no c"): "factor −c is missing",
            ("check_swapped_pair", "two largest"): "two largest distances",
            ("check_swapped_pair", "one-based"): "1-based",
        },
    )
