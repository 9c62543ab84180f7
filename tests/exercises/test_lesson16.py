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
