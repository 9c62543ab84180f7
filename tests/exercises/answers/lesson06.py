"""Lesson 06: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson06.py``.
"""

from __future__ import annotations

from orientviz.exercises.lesson06 import _line, _points, _skew

SOLUTIONS = {
    "check_essential": lambda R2, B: _skew(B) @ R2,
    "check_epipolar_line": lambda E, xy1, c: _line(E, xy1, c, True, True, True),
    "check_normal_case_points": lambda n1, n2, c, b: _points(n1, n2, c, b, 1.0, -1.0, False),
}

MUTANTS = {
    "check_essential": {
        "swapped": lambda R2, B: R2 @ _skew(B),
        "transposed_R": lambda R2, B: _skew(B) @ R2.T,
        "skew_transposed": lambda R2, B: _skew(B).T @ R2,
    },
    "check_epipolar_line": {
        "E_not_transposed": lambda E, xy1, c: _line(E, xy1, c, False, True, True),
        "no_c": lambda E, xy1, c: _line(E, xy1, c, True, False, True),
        "not_normalised": lambda E, xy1, c: _line(E, xy1, c, True, True, False),
    },
    "check_normal_case_points": {
        "parallax_sign": lambda n1, n2, c, b: _points(n1, n2, c, b, -1.0, -1.0, False),
        "z_sign": lambda n1, n2, c, b: _points(n1, n2, c, b, 1.0, 1.0, False),
        "y_parallax": lambda n1, n2, c, b: _points(n1, n2, c, b, 1.0, -1.0, True),
    },
}
