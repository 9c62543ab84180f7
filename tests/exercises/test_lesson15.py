"""Lesson 15's checkers: solutions pass, blanks are 'not written yet', mutants fail by far."""

from answers import lesson15 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson15


def test_checks():
    assert_module_checks(lesson15, answers)


def test_diagnoses_name_the_mistake():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson15,
        answers,
        {
            ("check_smallest_redundancy", "one-sided"): "one-sided",
            ("check_smallest_redundancy", "squared"): "bound for σ̂0²",
            ("check_smallest_redundancy", "off by one"): "off by one",
            ("check_expected_rms", "no r"): "σ_v = σ √r",
            ("check_expected_rms", "no sqrt"): "square root is missing",
            ("check_expected_rms", "r squared"): "r enters squared",
        },
    )


def test_false_alarms_check_counts_at_the_first_level_that_finds_more(capsys):
    import pytest

    from orientviz.exercises._common import CheckFailed, NotWrittenError

    blunders = {"a/1", "b/2", "c/3"}
    runs = {  # what a data snooping would eliminate at each level (%)
        0.01: {"a/1", "x/9"},
        0.1: {"a/1", "x/9", "y/8"},
        1.0: {"a/1", "b/2", "x/9", "y/8", "z/7", "w/6"},
        5.0: {"a/1", "b/2", "x/9", "y/8", "z/7", "w/6", "v/5", "u/4", "t/3"},
    }
    calls = []

    def clean(alpha):
        calls.append(alpha)
        return runs[alpha]

    lesson15.check_false_alarms(lambda: 4, clean, blunders)  # at 1 %: 6 eliminated, 2 blunders
    assert capsys.readouterr().out.startswith("✓")
    assert sorted(set(calls)) == [0.01, 0.1, 1.0, 5.0]
    with pytest.raises(CheckFailed, match="all rays eliminated"):
        lesson15.check_false_alarms(6, clean, blunders)
    with pytest.raises(CheckFailed, match="α0 = 5 %"):
        lesson15.check_false_alarms(7, clean, blunders)
    with pytest.raises(CheckFailed, match="blunders found"):
        lesson15.check_false_alarms(2, clean, blunders)
    with pytest.raises(NotWrittenError):
        lesson15.check_false_alarms(None, clean, blunders)


def test_residual_pattern_check_refuses_the_engine():
    import numpy as np

    from orientviz.adjust import gauss_newton
    from orientviz.exercises._common import rejection

    def engine(xy, w):  # the lesson's stand-in
        A4 = np.zeros((2 * len(xy), 4))
        A4[0::2, 0], A4[1::2, 1] = 1, 1
        A4[0::2, 2], A4[1::2, 2], A4[0::2, 3], A4[1::2, 3] = xy[:, 0], xy[:, 1], -xy[:, 1], xy[:, 0]
        p = gauss_newton(lambda q: (A4 @ q, A4), np.zeros(4), w.ravel(), 0.005).x
        return p[:2], p[2], p[3]

    exc = rejection(lesson15.check_residual_pattern, engine)
    assert exc is not None and "calls the library's gauss_newton" in str(exc)


def test_the_lessons_stand_in_is_refused_and_named():
    from mutants import assert_diagnoses

    for text in ["calls the library's expected_rms_library", "stand-in"]:
        assert_diagnoses(lesson15, answers, {("check_expected_rms", "the stand-in"): text})


def test_import_mistakes_are_explained():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson15,
        answers,
        {
            ("check_import_mistakes", "mirror as a rotation"): "'v not flipped'. (v) What does",
            ("check_import_mistakes", "principal point as none"): "(principal point) By how much",
            ("check_import_mistakes", "pixel size as a scale"): "(pixel size) Which quantities",
        },
    )


def test_import_mistakes_do_not_give_the_answer_away():
    from orientviz.exercises._common import rejection

    exc = rejection(
        lesson15.check_import_mistakes,
        answers.MUTANTS["check_import_mistakes"]["mirror as a scale"],
    )
    assert exc is not None and "no pattern" not in str(exc) and "mirror" not in str(exc)
