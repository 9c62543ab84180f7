"""Geier's construction of a radar image point and the shaded surfaces, without a browser."""

import numpy as np
import pytest

from orientviz.radar import geier1973 as G
from orientviz.radar.ppi import horizontal_range, project
from orientviz.viewer.radar_geometry import (
    cap_mesh,
    disc_mesh,
    geier_construction,
    polyline_to_segments,
)


def _area(V, F):
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()


def test_disc_lies_in_its_plane_with_its_radius():
    n = np.array([0.3, -0.2, 0.9])
    V, F = disc_mesh([1.0, 2.0, 3.0], n, 5.0, n=64)
    assert V.shape == (65, 3) and F.shape == (64, 3) and F.max() == 64
    np.testing.assert_allclose((V - [1.0, 2.0, 3.0]) @ n, 0.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(V[1:] - V[0], axis=1), 5.0)
    assert _area(V, F) == pytest.approx(np.pi * 25.0, rel=2e-3)  # a 64-gon


def test_cap_is_on_the_sphere_and_as_wide_as_asked():
    c, r, w = np.array([10.0, -5.0, 2.0]), 7.0, np.array([0.0, 1.0, 1.0])
    V, F = cap_mesh(c, r, w, np.radians(20.0))
    np.testing.assert_allclose(np.linalg.norm(V - c, axis=1), r)
    ang = np.degrees(np.arccos(np.clip((V - c) @ w / (r * np.linalg.norm(w)), -1, 1)))
    assert ang.max() == pytest.approx(20.0)
    np.testing.assert_allclose(V[0], c + r * w / np.linalg.norm(w))  # the pole first
    whole = cap_mesh(c, r, w, np.pi, 24, 64)
    assert _area(*whole) == pytest.approx(4 * np.pi * r**2, rel=5e-3)
    assert F.min() == 0 and F.max() == len(V) - 1


@pytest.mark.parametrize("image", [1, 2, 3])
def test_geier_construction_is_the_pythagoras_of_the_reduction(image):
    P = G.points("fig7")
    im = G.images()[image]
    xy = G.image_coordinates("fig7", image, rounded=False)
    for i in (0, 12, 14):
        con = geier_construction(P[i], xy[i], im)
        X0, s, h, s_e = con["station"], con["s"], con["h"], con["s_e"]
        assert s == pytest.approx(np.linalg.norm(P[i] - X0), rel=1e-12)  # sphere (4b)
        assert s_e == pytest.approx(horizontal_range(P[i : i + 1], im)[0], rel=1e-12)
        assert s_e**2 + h**2 == pytest.approx(s**2, rel=1e-12)
        assert np.linalg.norm(con["foot"] - X0) == pytest.approx(h)
        assert np.linalg.norm(con["image_point"] - con["foot"]) == pytest.approx(s_e)
        assert (con["foot"] - X0) @ im.axis < 0  # the ground plane below the station
        # the image point is where the circle meets the ground plane, and it has the
        # target's image coordinates: the image cannot tell the two apart
        np.testing.assert_allclose(project(con["image_point"][None], im)[0], xy[i], atol=1e-6)
        assert con["gap"] < 1e-6
        np.testing.assert_allclose(np.linalg.norm(con["circle"] - X0, axis=1), s, rtol=1e-12)
        np.testing.assert_allclose((con["circle"] - X0) @ con["normal"], 0.0, atol=1e-6)
        np.testing.assert_allclose(con["arc"][0], P[i], atol=1e-6)
        np.testing.assert_allclose(con["arc"][-1], con["image_point"], atol=1e-6)
        ring = con["range_ring"] - con["foot"]
        np.testing.assert_allclose(np.linalg.norm(ring, axis=1), s_e, rtol=1e-12)
        np.testing.assert_allclose(ring @ im.axis, 0.0, atol=1e-6)


def test_rounded_coordinates_put_the_target_off_its_circle():
    P, im = G.points("fig7"), G.images()[3]
    xy = G.image_coordinates("fig7", 3, rounded=True)
    con = geier_construction(P[14], xy[14], im)
    assert 1e-3 < con["gap"] < 2.0  # within a metre or so of the rounding
    seg = polyline_to_segments(con["circle"])
    assert seg.shape == (len(con["circle"]) - 1, 2, 3)
    np.testing.assert_array_equal(seg[1:, 0], seg[:-1, 1])
