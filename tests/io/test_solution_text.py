"""The text report prints each parameter to the digits its σ carries."""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.io.solution import _value_to_sigma


@pytest.mark.parametrize("seed", range(5))
def test_printed_value_reaches_the_third_digit_of_sigma(seed):
    rng = np.random.default_rng(seed)
    for _ in range(400):
        sigma = 10.0 ** rng.uniform(-12, 4)
        value = rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(-13, 5)
        text = _value_to_sigma(value, sigma)
        last_digit = 10.0 ** (np.floor(np.log10(sigma)) - 2)
        bound = 0.5 * last_digit + abs(value) * 4.5e-16  # + two ulps of a double
        assert abs(float(text) - value) <= bound, (value, sigma, text)
        if abs(value) > last_digit:  # a value σ can see never prints as zero
            assert float(text) != 0.0, (value, sigma, text)


def test_small_lens_terms_are_not_rounded_away():
    # DBAT's K3 of the camcal demo is about -2e-6 mm^-6 with σ 1e-7: six fixed
    # decimals printed it as -0.000002, losing everything but the sign.
    assert _value_to_sigma(-2.0534e-06, 1.01e-07) == "-2.053e-06"
    assert _value_to_sigma(2336.807891, 0.328) == "2336.808"


def test_values_without_sigma_keep_six_decimals_and_missing_values_a_dash():
    assert _value_to_sigma(1.23456789, 0.0) == "1.234568"
    assert _value_to_sigma(float("nan"), 0.1) == "—"


def test_without_redundancy_numbers_nothing_is_said_to_be_flagged():
    """No w, no test: the report says "not tested", not "flagged: none" (the independent
    models method gives no redundancy numbers; a bundle whose precision could not be computed —
    e.g. points near infinity at a state the precision cannot invert — neither)."""
    import orientviz as ov

    models = ov.solve_problem(ov.load_dataset("block_strip"), method="models").as_text()
    assert "flagged (|w| > 3.29): not tested (no redundancy numbers)" in models
    assert "no redundancy numbers: this method gives none" in models
    sol = ov.solve_problem(ov.load_dataset("block_strip"))
    assert "flagged (|w| > 3.29): not tested" not in sol.as_text()
    sol.adjustment.normalized_residuals = None  # as bundle/loop/_finish leaves it then
    sol.adjustment.precision_error = "no precision at the last state: …"
    text = sol.as_text()
    assert "flagged (|w| > 3.29): not tested (no redundancy numbers)" in text
    assert "no redundancy numbers: the precision was not computed" in text
    assert "flagged (|w| > 3.29): none" not in text


def test_one_iteration_is_singular(tmp_path):
    """A solved file solved again stops after one step: "1 iteration", not "1 iterations"."""
    from orientviz.cli import main
    from orientviz.io.problem import load_problem
    from orientviz.io.solve import solve_problem

    out = tmp_path / "s.json"
    assert main(["solve", "block_strip", "-o", str(out)]) == 0
    text = solve_problem(load_problem(out)).as_text()
    assert "1 iteration, converged: corrections below" in text and "after 1 iteration\n" in text
    assert "iterations" not in text.split("\n")[2]
