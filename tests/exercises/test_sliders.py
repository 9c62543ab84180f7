"""Checks of the answers read off a lesson's slider (orientviz.exercises.sliders)."""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.exercises import sliders
from orientviz.exercises._common import CheckFailed, NotWrittenError


def test_crossing_finds_the_first_level_crossing():
    assert sliders.crossing(lambda t: t**2, 2.0, 0.0, 10.0) == pytest.approx(np.sqrt(2.0), 1e-7)
    with pytest.raises(ValueError):
        sliders.crossing(lambda t: t, 20.0, 0.0, 10.0)


def test_generic_check_accepts_one_step_and_names_misreadings(capsys):
    sliders.check_slider_answer("x", 10.4, 10.0, 0.5, "m")
    assert capsys.readouterr().out.startswith("✓")
    with pytest.raises(NotWrittenError):
        sliders.check_slider_answer("x", None, 10.0, 0.5, "m")
    with pytest.raises(CheckFailed, match="in km"):
        sliders.check_slider_answer("x", 0.01, 10.0, 0.5, "m", [("in km", 0.01)])
    with pytest.raises(CheckFailed, match="too large"):
        sliders.check_slider_answer("x", 12.0, 10.0, 0.5, "m")


@pytest.fixture(scope="module")
def pair_case():
    from orientviz.orientation.plotter import config_with, true_pair

    pair = true_pair(config_with(relief=0.10, sequence="opk", sigma_by=0.0, sigma_z=0.0),
                     rng=np.random.default_rng(3))  # fmt: skip
    return pair, pair.elements.copy()


def test_pair_kappa_check(pair_case, capsys):
    pair, settings = pair_case
    # an independent look: the RMS parallax at the nine points grows linearly with κ here
    r1 = sliders.pair_parallax_rms(pair, settings, 1.0)[0]
    expected = 0.050 / r1
    sliders.check_pair_kappa(round(expected, 1), pair, settings, 0.050, 0.1)
    assert "✓" in capsys.readouterr().out
    sliders.check_pair_kappa(-round(expected, 1), pair, settings, 0.050, 0.1)  # either sign
    largest = 0.050 / sliders.pair_parallax_rms(pair, settings, 1.0)[1]
    with pytest.raises(CheckFailed, match="LARGEST"):
        sliders.check_pair_kappa(largest, pair, settings, 0.050, 0.1)
    with pytest.raises(CheckFailed, match="radians"):
        sliders.check_pair_kappa(expected / 6366.2, pair, settings, 0.050, 0.1)
    with pytest.raises(NotWrittenError):
        sliders.check_pair_kappa(None, pair, settings, 0.050, 0.1)


def test_trilateration_check(capsys):
    from orientviz.radar import geier1973 as G

    P, X0 = G.points("fig7")[[0, 4, 22]], np.array(G.images()[2].X0)
    r = np.linalg.norm(P - X0, axis=1)
    # brute force: the candidate moves by the same amount for δ found on a fine scan
    ts = np.arange(0.0, 60.0, 0.01)
    d = np.array([sliders.trilateration_shift(P, r, X0, t) for t in ts[::100]])
    assert np.all(np.diff(d) > 0)
    fine = ts[np.argmax([sliders.trilateration_shift(P, r, X0, t) >= 100.0 for t in ts])]
    sliders.check_trilateration_delta(round(fine * 2) / 2, P, r, X0, 100.0, 0.5)
    assert "✓" in capsys.readouterr().out
    with pytest.raises(CheckFailed, match="the shift itself"):
        sliders.check_trilateration_delta(100.0, P, r, X0, 100.0, 0.5)
    with pytest.raises(CheckFailed, match="too small"):
        sliders.check_trilateration_delta(fine - 5.0, P, r, X0, 100.0, 0.5)
