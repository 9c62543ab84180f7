"""Lesson 16's checkers: solutions pass, blanks are 'not written yet', mutants fail by far;
the by-hand task really needs two points (one is not enough, the witness pair is)."""

from answers import lesson16 as answers
from mutants import assert_module_checks

from orientviz.exercises import lesson16


def test_checks():
    assert_module_checks(lesson16, answers)


def test_the_task_needs_two_points_and_the_witness_reaches_the_target():
    block = lesson16._design_block()
    assert block.n_images == 27
    assert lesson16.worst_sigma_z(block, []) > 10 * lesson16.TARGET_SIGMA_Z
    assert lesson16.FEWEST == 2
    pair = answers.SOLUTIONS["check_by_hand"]()
    assert len(pair) == 2
    assert lesson16.worst_sigma_z(block, pair) <= lesson16.TARGET_SIGMA_Z


def test_control_sigma_check_agrees_with_the_woodbury_update_and_names_misreadings(capsys):
    import numpy as np
    import pytest

    from orientviz.exercises._common import CheckFailed, NotWrittenError

    rng = np.random.default_rng(16)
    L = rng.normal(size=(12, 12)) * np.repeat([1.0, 0.3, 2.0, 0.5], 3)[:, None]
    Q = L @ L.T + 0.01 * np.eye(12)  # cofactors of 4 points (XYZ each), strongly correlated
    j = 2

    def others(sigma):  # an independent look: the Woodbury update of the lesson
        idx = [3 * j, 3 * j + 1, 3 * j + 2]
        M = np.linalg.inv(np.eye(3) * sigma**2 + Q[np.ix_(idx, idx)])
        Qn = Q - Q[:, idx] @ M @ Q[:, idx].T
        return np.delete(np.sqrt(np.diag(Qn)[2::3]), j).max()

    target = 1.1 * others(1e-6)
    grid = np.arange(0.001, 20.0, 0.002)
    want = next(s for s in grid if others(s) >= target)
    lesson16.check_control_sigma(round(want, 2), Q, j, step=0.02)
    assert capsys.readouterr().out.startswith("✓")
    with pytest.raises(CheckFailed, match="largest σ_Z itself"):
        lesson16.check_control_sigma(target, Q, j, step=0.02)
    with pytest.raises(CheckFailed, match="in cm"):
        lesson16.check_control_sigma(want * 100, Q, j, step=0.02)
    with pytest.raises(NotWrittenError):
        lesson16.check_control_sigma(None, Q, j, step=0.02)


def test_largest_scale_mistakes_are_named():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson16,
        answers,
        {
            ("check_largest_scale", "no √2"): "√2 is missing",
            ("check_largest_scale", "p"): "not 1 − p",
            ("check_largest_scale", "no μ"): "μ_z(i) left out",
            ("check_largest_scale", "B/H"): "upside down",
        },
    )


def test_the_lessons_stand_in_is_refused_and_named():
    from mutants import assert_diagnoses

    for text in ["hands a 11 × 11 matrix to np.linalg.inv", "control_update_library"]:
        assert_diagnoses(
            lesson16,
            answers,
            {("check_control_update", "the stand-in (a new u × u inverse)"): text},
        )


def test_control_update_check_refuses_solving_with_the_enlarged_n():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson16, answers, {("check_control_update", "solve on the enlarged N"): "to np.linalg."}
    )


def test_after_worst_mistakes_are_named():
    from mutants import assert_diagnoses

    assert_diagnoses(
        lesson16,
        answers,
        {
            ("check_after_worst", "itself"): "AFTERWARDS",
            ("check_after_worst", "variance"): "variance",
            ("check_after_worst", "before"): "BEFORE the control point",
        },
    )
