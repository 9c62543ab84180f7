"""Lesson 01's checkers pass the solutions and reject every plausible wrong answer by far."""

from __future__ import annotations

from mutants import assert_module_checks

from orientviz.exercises import lesson01


def test_lesson01_checks():
    assert_module_checks(lesson01)
