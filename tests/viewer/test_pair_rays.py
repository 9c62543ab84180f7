"""Rays of a pair point, their gap, the epipolar plane and the normalised images."""

import numpy as np
import pytest

from orientviz.orientation.plotter import AnalogPlotter, PlotterConfig, true_pair
from orientviz.viewer.epipolar_picture import normalised_picture, picture_exaggeration
from orientviz.viewer.pair_rays import normalised_pair, plane_mesh, point_rays


@pytest.fixture
def plotter():
    pair = true_pair(PlotterConfig(sigma_by=0.0, sigma_z=0.0), rng=np.random.default_rng(3))
    return AnalogPlotter(pair)


def scheme(pl):
    return np.column_stack(pl.scheme_points())


def test_rays_meet_in_the_point_when_the_dials_are_right(plotter):
    plotter.settings[:] = plotter.pair.elements
    for P in scheme(plotter):
        pr = point_rays(plotter, P)
        assert pr["gap_length"] < 1e-9 and abs(pr["p_y"]) < 1e-9
        assert abs(pr["right_off_plane"]) < 1e-9
        np.testing.assert_allclose(pr["closest"], [P, P], atol=1e-9)  # they meet in the point


def test_gap_is_the_shortest_segment_and_leaves_the_epipolar_plane(plotter):
    P = scheme(plotter)[2]
    pr = point_rays(plotter, P)
    (O1, O2), (d1, d2) = pr["centres"], pr["directions"]
    gap = pr["gap"]
    # the shortest segment is perpendicular to both rays, and both ends lie on their ray
    assert abs(gap @ d1) < 1e-9 * pr["gap_length"] + 1e-12
    assert abs(gap @ d2) < 1e-9 * pr["gap_length"] + 1e-12
    for end, O, d in zip(pr["closest"], (O1, O2), (d1, d2), strict=True):
        assert np.linalg.norm(np.cross(end - O, d)) < 1e-9
    # no other pair of points on the two rays is closer (sampled around the closest ones)
    t = np.linspace(-5, 5, 21)
    a = pr["closest"][0] + t[:, None, None] * d1
    b = pr["closest"][1] + t[None, :, None] * d2
    assert np.linalg.norm(a - b, axis=2).min() >= pr["gap_length"] - 1e-9
    # before orientation the rays miss by millimetres, mostly across the base
    assert pr["gap_length"] > 1.0 and abs(gap[1]) > abs(gap[0])
    # the plane holds O1, O2 and the left ray; the right ray's end is off it by the gap's
    # component along the normal
    n = pr["plane_normal"]
    np.testing.assert_allclose((pr["plane"] - O1) @ n, 0.0, atol=1e-9)
    assert pr["right_off_plane"] == pytest.approx(gap @ n)
    V, F = plane_mesh(pr["plane"])
    assert F.shape == (2, 3) and set(F.ravel()) == {0, 1, 2, 3}


def test_a_dial_changes_the_gap_continuously(plotter):
    P = scheme(plotter)[0]
    plotter.settings[:] = plotter.pair.elements
    plotter.settings[4] += 1e-4  # κ by 0.64 c
    small = point_rays(plotter, P)["gap_length"]
    plotter.settings[4] += 1e-4
    double = point_rays(plotter, P)["gap_length"]
    assert 0 < small and double == pytest.approx(2 * small, rel=0.01)  # linear for small dκ


def test_normalised_images_have_rows_as_epipolar_lines(plotter):
    S = scheme(plotter)
    before = normalised_pair(plotter, S)
    assert np.sqrt(np.mean(before["p_y"] ** 2)) > 0.1  # start: 100-150 c off
    plotter.settings[:] = plotter.pair.elements
    after = normalised_pair(plotter, S)
    np.testing.assert_allclose(after["p_y"], 0.0, atol=1e-9)
    np.testing.assert_allclose(after["R_n"] @ after["R_n"].T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(
        after["R_n"][:, 0], plotter.state.base / np.linalg.norm(plotter.state.base)
    )


def test_picture_shows_points_bars_and_the_selected_row(plotter):
    S = scheme(plotter)
    norm = normalised_pair(plotter, S)
    pic, k = normalised_picture(norm, selected=4, width=320)
    assert pic.dtype == np.uint8 and pic.shape[1] == 320 and pic.shape[2] == 3
    colours = {tuple(c) for c in pic.reshape(-1, 3)}
    assert {(200, 0, 130), (250, 130, 0), (0, 140, 170)} <= colours  # selected, row, bars
    plotter.settings[:] = plotter.pair.elements
    pic0, k0 = normalised_picture(normalised_pair(plotter, S), selected=None, width=320)
    assert k0 == 1.0 and (250, 130, 0) not in {tuple(c) for c in pic0.reshape(-1, 3)}
    assert picture_exaggeration(np.array([0.0, 0.0]), 1.0) == 1.0
    assert picture_exaggeration(np.array([0.01] * 10), 0.5) == pytest.approx(600.0)
