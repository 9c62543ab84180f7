"""Degenerate geometry gives a diagnostic that names what is not determinable."""

import numpy as np
import pytest

import orientviz as ov
from orientviz.radar import geier1973 as G
from orientviz.radar.diagnostics import pair_geometry, weakest_direction
from orientviz.radar.orientation import calibrate, exterior, station_by_trilateration
from orientviz.radar.pair import intersect, relative_orientation
from orientviz.radar.ppi import project
from orientviz.radar.trilateration import trilaterate_three

T = G.images()


def test_three_collinear_points_trilateration():
    P = np.array([[0.0, 0.0, -15000.0], [10000.0, 0.0, -15000.0], [20000.0, 0.0, -15000.0]])
    with pytest.raises(ov.NotDeterminableError) as exc:
        trilaterate_three(P, [20000.0, 21000.0, 22000.0])
    assert exc.value.parameters == ["X0", "Y0", "Z0"] and "one line" in str(exc.value)


def test_points_on_a_line_least_squares_names_station():
    # five points on one line: the station may turn about it
    P = np.column_stack([np.linspace(-20000, 20000, 5), np.zeros(5), np.full(5, -15000.0)])
    xy = project(P, T[2])
    with pytest.raises(ov.NotDeterminableError) as exc:
        station_by_trilateration(P, xy, T[2])
    assert set(exc.value.parameters) & {"Y0", "Z0"}


def test_fewer_observations_than_unknowns():
    P, xy = G.points("fig7")[:2], G.image_coordinates("fig7", 2)[:2]
    with pytest.raises(ov.NotDeterminableError, match="4 observations for 5 unknowns") as exc:
        calibrate(P, xy, T[2])
    assert exc.value.parameters == ["x0", "y0", "h", "m", "kappa"]
    with pytest.raises(ov.NotDeterminableError, match="need at least 3"):
        station_by_trilateration(P, xy, T[2])
    xy1 = G.image_coordinates("fig7", 1)[:5]
    with pytest.raises(ov.NotDeterminableError, match="5 homologous points"):
        relative_orientation(xy1, T[1], G.image_coordinates("fig7", 2)[:5], T[2])


def test_coincident_azimuth_planes_relative_orientation_singular():
    # image 2 straight above image 1 on the same vertical axis: every ε2 = ε1, so a shift
    # of station 2 along the common axis moves every point along its projection circle
    # without changing any image coordinate; the engine names the parameters involved
    im2 = T[1].with_(X0=(0.0, 0.0, 2000.0))
    P = G.points("fig7")
    xy1, xy2 = project(P, T[1]), project(P, im2)
    geo = pair_geometry(xy1, T[1], xy2, im2, P)
    assert np.all(geo.plane_angle < 1e-9) and geo.weak.all()
    with pytest.raises(ov.NotDeterminableError) as exc:
        relative_orientation(xy1, T[1], xy2, im2.with_(kappa=0.01), points0=P)
    assert exc.value.defect >= 1 and "Z0" in exc.value.parameters


def test_near_parallel_planes_flagged_in_the_near_normal_pair():
    P = G.points("fig7")
    xy1, xy2 = project(P, T[1]), project(P, T[2])
    geo = pair_geometry(xy1, T[1], xy2, T[2], P)
    # the row Y = 0 lies (almost) on the line through both stations
    weak_rows = set(np.flatnonzero(geo.plane_angle < 0.01) // 5)
    assert weak_rows == {2}
    assert "nearly parallel" in geo.summary()


def test_tangent_line_flagged():
    # ε1 ∩ ε2 through X perpendicular to station 1's ray: the line touches sphere 1.
    # Image 1: vertical axis at the origin, so ε1 is the plane y = 0 for X below.
    im1 = T[1].with_(kappa=0.0)
    X = np.array([10000.0, 0.0, -15000.0])
    d = np.array([15000.0, 0.0, 10000.0]) / np.hypot(15000.0, 10000.0)  # ⟂ X, in y = 0
    # image 2's axis along d, station off the plane: ε2 is spanned by d and the y axis
    im2 = im1.with_(
        X0=tuple(X - 20000.0 * d + [0.0, 5000.0, 0.0]), phi=float(np.arctan2(d[0], d[2]))
    )
    P = np.vstack([X, [30000.0, 20000.0, -14000.0]])
    xy1, xy2 = project(P, im1), project(P, im2)
    geo = pair_geometry(xy1, im1, xy2, im2, P)
    assert geo.tangency1[0] < 1e-9 and geo.weak[0]
    assert geo.tangency1[1] > 0.05  # the other point is an ordinary one
    np.testing.assert_allclose(intersect(xy1, im1, xy2, im2)[1], P[1], atol=1e-5)


def test_weakest_direction_of_near_normal_relative_orientation():
    xy1, xy2 = G.image_coordinates("plane", 1), G.image_coordinates("plane", 2)
    res = relative_orientation(xy1, T[1], xy2, T[2], damping="lm")
    cond, involved = weakest_direction(res, block="image2")
    names = [n for n, _ in involved[:3]]
    assert {"X0", "Z0", "phi"} == set(names), involved
    assert cond > 100


def test_bad_observe_and_stopping_names():
    P, xy = G.points("fig7"), G.image_coordinates("fig7", 2)
    with pytest.raises(ov.InputError, match="stopping"):
        exterior(P, xy, T[2], stopping="never")
