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


def test_tilt_check_against_the_projection(capsys):
    from orientviz.camera import project
    from orientviz.rotation import matrix_from_opk

    # the closed form agrees with the library's projection of a tilted camera
    P = np.array([[100.0, 0.0, -150.0]]) * 10
    for phi_c in (0.5, 3.0, 9.0):
        xy = project(P, np.zeros(3), matrix_from_opk(0.0, phi_c * np.pi / 20000, 0.0), 150.0)
        assert sliders.tilt_shift_um(100.0, 150.0, phi_c) == pytest.approx(
            abs(xy[0, 0] - 100.0) * 1000, rel=2e-3
        )
    sliders.check_tilt(lambda: 3.0, 100.0, 150.0, 100.0, 0.1)
    assert "✓" in capsys.readouterr().out
    with pytest.raises(CheckFailed, match="CENTRE"):
        sliders.check_tilt(lambda: 4.2, 100.0, 150.0, 100.0, 0.1)
    with pytest.raises(CheckFailed, match="in cc"):
        sliders.check_tilt(lambda: 294.0, 100.0, 150.0, 100.0, 0.1)
    with pytest.raises(NotWrittenError):
        sliders.check_tilt(lambda: None, 100.0, 150.0, 100.0, 0.1)


def test_base_height_check_against_the_library_intersection():
    from orientviz.orientation.intersection import intersect_points  # noqa: F401 (present)
    from orientviz.widgets.resection import intersection_state

    for bh in (0.3, 0.7, 1.2):  # the closed form is the library's σ_Z of the middle point
        assert sliders.normal_case_sigma_z(bh, 1500.0, 152.7, 5.0) == pytest.approx(
            intersection_state(bh).std()[1][2], rel=1e-6
        )
    sliders.check_base_height(0.70, 1500.0, 152.7, 5.0, 0.10, 0.01)
    with pytest.raises(CheckFailed, match="σ_Z equals σ_X"):
        sliders.check_base_height(1.41, 1500.0, 152.7, 5.0, 0.10, 0.01)


def test_similarity_and_model_checks():
    # σ of the scale is linear in the control σ (up to the noise's effect on the estimated
    # scale it is divided by, ~2e-5 here): the crossing is where that line meets the target
    q = sliders.similarity_scale_ppm("clustered", 1.0)
    assert sliders.similarity_scale_ppm("clustered", 3.0) == pytest.approx(3 * q, rel=1e-4)
    sliders.check_similarity_scale(round(50.0 / q, 1), "clustered", 50.0, 0.1)
    with pytest.raises(CheckFailed, match="in m"):
        sliders.check_similarity_scale(50.0 / q / 100, "clustered", 50.0, 0.1)
    z1 = sliders.model_radial_z_cm(1.0)
    sliders.check_model_radial(round(2 * 5.0 / z1) / 2, 5.0, 0.5)
    with pytest.raises(CheckFailed, match="PLANIMETRIC"):
        sliders.check_model_radial(287.0, 5.0, 0.5)


def test_event_check():
    sliders.check_event_at("e", 2.0, lambda v: v >= 1.95, 0.1, "m", 0.1, 3.0)
    with pytest.raises(CheckFailed, match="does not happen yet"):
        sliders.check_event_at("e", 1.9, lambda v: v >= 1.95, 0.1, "m", 0.1, 3.0)
    with pytest.raises(CheckFailed, match="smallest value"):
        sliders.check_event_at("e", 2.5, lambda v: v >= 1.95, 0.1, "m", 0.1, 3.0)
    with pytest.raises(CheckFailed, match="outside"):
        sliders.check_event_at("e", 9.0, lambda v: v >= 1.95, 0.1, "m", 0.1, 3.0)


def test_first_event_bisects_over_the_slider_positions():
    calls = []

    def happens(v):
        calls.append(v)
        return v >= 2.26

    assert sliders.first_event(happens, 0.0, 5.0, 0.25) == pytest.approx(2.5)
    assert len(calls) <= 8  # bisection, not a scan of the 21 positions
    assert sliders.first_event(lambda v: v >= -1.0, 0.0, 5.0, 0.25) == 0.0
    with pytest.raises(ValueError):
        sliders.first_event(lambda v: v > 9.0, 0.0, 5.0, 0.25)
