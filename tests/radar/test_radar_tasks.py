"""Each orientation task recovers the truth exactly from error-free image coordinates."""

import numpy as np
import pytest

import orientviz as ov
from orientviz.radar import geier1973 as G
from orientviz.radar.orientation import (
    calibrate,
    exterior,
    resect_all,
    rotations,
    station_by_trilateration,
)
from orientviz.radar.pair import absolute_orientation, intersect, relative_orientation
from orientviz.radar.ppi import PARAMS
from orientviz.radar.trilateration import trilaterate_three

TRUE = G.images()
APPROX = G.approximations()
# error-free data: the solution must reproduce the truth to the accuracy of the
# iteration (corrections < 1e-8 σ) and floating point, far below 1e-6 m
EXACT_M = 1e-6
EXACT_RAD = 1e-10


def _err(res, truth, names):
    est = res.image.vector()
    idx = [PARAMS.index(n) for n in names]
    return np.abs(est[idx] - truth.vector()[idx])


def _assert_exact(res, truth, names):
    e = _err(res, truth, names)
    tol = np.array([EXACT_RAD if n in ("phi", "omega", "kappa") else EXACT_M for n in names])
    tol[[i for i, n in enumerate(names) if n == "m"]] = 1e-12
    assert np.all(e < tol), dict(zip(names, e))
    assert res.sigma0 < 1e-6


@pytest.mark.parametrize("surface", ["fig7", "plane", "sphere150_concave"])
def test_calibration_exact(surface):
    P, xy = G.points(surface), G.image_coordinates(surface, 2, rounded=False)
    a = APPROX[2]
    res = calibrate(P, xy, TRUE[2].with_(x0=a.x0, y0=a.y0, h=a.h, m=a.m, kappa=G.alpha0_approx()))
    _assert_exact(res, TRUE[2], ["x0", "y0", "h", "m", "kappa"])
    assert res.names == ["x0", "y0", "h", "m", "kappa"] and res.redundancy == 45


def test_exterior_and_rotations_exact():
    P, xy = G.points("fig7"), G.image_coordinates("fig7", 2, rounded=False)
    start = TRUE[2].with_(X0=APPROX[2].X0, phi=0.0, omega=0.0, kappa=0.0)
    _assert_exact(exterior(P, xy, start), TRUE[2], list(PARAMS[4:]))
    rot = rotations(P, xy, TRUE[2].with_(phi=0.0, omega=0.0, kappa=0.0))
    _assert_exact(rot, TRUE[2], ["phi", "omega", "kappa"])
    assert rot.redundancy == 22  # 25 tangential components, 3 unknowns


def test_all_ten_parameters_exact():
    P, xy = G.points("fig7"), G.image_coordinates("fig7", 3, rounded=False)
    _assert_exact(resect_all(P, xy, APPROX[3]), TRUE[3], list(PARAMS))


def test_trilateration_closed_form_both_candidates():
    P = G.points("fig7")[[0, 4, 22]]
    X0 = np.array(TRUE[2].X0)
    lo, hi, disc = trilaterate_three(P, np.linalg.norm(P - X0, axis=1))
    np.testing.assert_allclose(hi, X0, atol=1e-6)
    # the other candidate is the mirror image in the plane of the three points
    n = np.cross(P[1] - P[0], P[2] - P[0])
    n /= np.linalg.norm(n)
    np.testing.assert_allclose(lo, X0 - 2 * ((X0 - P[0]) @ n) * n, atol=1e-6)
    assert disc > 0


def test_trilateration_least_squares_exact():
    P, xy = G.points("fig7"), G.image_coordinates("fig7", 2, rounded=False)
    res = station_by_trilateration(P, xy, TRUE[2].with_(X0=(0.0, 0.0, 0.0)))
    _assert_exact(res, TRUE[2], ["X0", "Y0", "Z0"])
    assert res.candidates.shape == (2, 3)
    tri = [0, 4, 22]  # a wide, nearly horizontal triangle: the mirror lies below it
    low = station_by_trilateration(P[tri], xy[tri], TRUE[2], upper=False)
    assert low.image.X0[2] < -25000
    np.testing.assert_allclose(low.image.X0, low.candidates[0], atol=1e-6)


def test_intersection_and_relative_orientation_exact():
    P = G.points("sphere150_convex")
    xy1 = G.image_coordinates("sphere150_convex", 1, rounded=False)
    xy2 = G.image_coordinates("sphere150_convex", 2, rounded=False)
    np.testing.assert_allclose(intersect(xy1, TRUE[1], xy2, TRUE[2]), P, atol=1e-6)
    start = TRUE[2].with_(X0=APPROX[2].X0, phi=0.0, omega=0.0, kappa=0.0)
    res = relative_orientation(xy1, TRUE[1], xy2, start)
    e = _err(res, TRUE[2], list(PARAMS[4:]))
    assert np.all(e[:3] < 1e-5) and np.all(e[3:] < 1e-9), e
    np.testing.assert_allclose(res.points, P, atol=1e-5)
    assert res.redundancy == 25 - 6


def test_absolute_orientation_exact_and_no_scale():
    rng = np.random.default_rng(7)
    x = rng.uniform(-5000, 5000, (6, 3))
    R = ov.matrix_from_opk(0.02, -0.03, 0.4, "pok")
    T = np.array([1000.0, -200.0, 50.0])
    X = T + x @ R.T
    res = absolute_orientation(x, X)
    np.testing.assert_allclose(res.x, [*T, -0.03, 0.02, 0.4], atol=1e-9)
    ctrl = X.copy()
    ctrl[2:, :2] = np.nan  # 2 full points + heights only
    np.testing.assert_allclose(absolute_orientation(x, ctrl).x, res.x, atol=1e-8)
    with pytest.raises(ov.NotDeterminableError, match="6 unknowns"):
        absolute_orientation(x[:1], X[:1])


def test_trilateration_candidates_property():
    from hypothesis import given, settings
    from hypothesis import strategies as st

    coord = st.floats(-50000, 50000, allow_nan=False)

    @settings(max_examples=60, deadline=None, derandomize=True)
    @given(st.lists(st.tuples(coord, coord, st.floats(-17000, -14000)), min_size=3, max_size=3),
           st.tuples(coord, coord, st.floats(-2000, 2000)))  # fmt: skip
    def check(centres, station):
        C, X = np.array(centres), np.array(station)
        n = np.cross(C[1] - C[0], C[2] - C[0])
        scale = max(np.linalg.norm(C[1] - C[0]), np.linalg.norm(C[2] - C[0]), 1.0)
        if np.linalg.norm(n) < 1e-3 * scale**2:  # skip (nearly) collinear centres
            return
        r = np.linalg.norm(C - X, axis=1)
        lo, hi, disc = trilaterate_three(C, r)
        # both candidates lie on all three spheres; one of them is the station
        for q in (lo, hi):
            np.testing.assert_allclose(np.linalg.norm(C - q, axis=1), r, rtol=1e-7, atol=1e-3)
        assert min(np.linalg.norm(lo - X), np.linalg.norm(hi - X)) < 1e-3 * max(1.0, r.max() / 1e4)

    check()
