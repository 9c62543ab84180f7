"""Jacobians of the task models against central differences; the stopping rule."""

import numpy as np

from orientviz.radar import geier1973 as G
from orientviz.radar.orientation import image_equations
from orientviz.radar.pair import intersect, relative_equations, relative_orientation
from orientviz.radar.ppi import PARAMS
from orientviz.radar.stopping import geier_iterate

T = G.images()


def _fd(model, u, steps):
    J = np.empty((model(u)[0].size, u.size))
    for k in range(u.size):
        d = np.zeros(u.size)
        d[k] = steps[k]
        J[:, k] = (model(u + d)[0] - model(u - d)[0]) / (2 * steps[k])
    return J


def _steps(names):
    return np.array([1e-7 if n in ("m", "phi", "omega", "kappa") else 1e-3 for n in names])


def test_radial_and_tangential_models_match_differences():
    P, xy = G.points("fig7"), G.image_coordinates("fig7", 3)
    for observe, free in (("radial", ("X0", "Y0", "Z0", "h", "m")), ("tangential", PARAMS)):
        model, u0, _ = image_equations(P, xy, T[3], free, observe)
        u = u0 + 0.001 * np.arange(len(u0))  # away from the truth: a generic point
        J = model(u)[1]
        # cancellation ε·1e5 m / step dominates: ≤ 2.2e-16·1e5/1e-7 ≈ 2e-4
        np.testing.assert_allclose(J, _fd(model, u, _steps(free)), rtol=1e-5, atol=5e-4)


def test_relative_orientation_jacobian_matches_differences():
    xy1, xy2 = G.image_coordinates("plane", 1), G.image_coordinates("plane", 2)
    X = intersect(xy1, T[1], xy2, T[2])
    model = relative_equations(T[1], T[2].with_(phi=0.001), PARAMS, len(X))
    u = np.concatenate([T[2].vector() + 1e-3, X.reshape(-1) + 1.0])
    names = list(PARAMS) + ["X"] * X.size
    np.testing.assert_allclose(model(u)[1], _fd(model, u, _steps(names)), rtol=1e-5, atol=5e-4)


def test_relative_orientation_with_the_second_interior_orientation_exact():
    # ten unknowns of image 2 (its interior orientation differs), image 1 fixed
    im2 = T[2].with_(x0=450.0, y0=690.0, h=15100.0, m=1.1270)
    P = G.points("sphere150_convex")
    xy1 = G.project(P, T[1])
    xy2 = G.project(P, im2)
    start = im2.with_(x0=440.0, y0=700.0, h=15050.0, m=1.1265, X0=(30030.0, 10.0, -1020.0))
    res = relative_orientation(xy1, T[1], xy2, start, free=PARAMS, damping="lm")
    e = np.abs(res.image.vector() - im2.vector())
    assert res.redundancy == 25 - 10
    assert np.all(e[[0, 1, 2, 4, 5, 6]] < 1e-4) and e[3] < 1e-9 and np.all(e[7:] < 1e-9), e


def test_geier_rule_keeps_the_previous_estimate_when_m0_grows():
    # calibration of column 10: the second linear solution raises m0, so the estimate
    # after the first step is kept and the iteration ends
    P, xy = G.points("cyl_x300_concave"), G.image_coordinates("cyl_x300_concave", 2)
    a = G.approximations()[2]
    start = T[2].with_(x0=a.x0, y0=a.y0, h=a.h, m=a.m, kappa=G.alpha0_approx())
    free = ("x0", "y0", "h", "m", "kappa")
    model, u0, l = image_equations(P, xy, start, free)
    res = geier_iterate(model, u0, l, names=list(free))
    assert "not applied" in res.reason and res.iterations == 1
    # the kept estimate is exactly one Gauss-Newton step from the start
    f, J = model(u0)
    step = np.linalg.solve(J.T @ J, J.T @ (l - f))
    np.testing.assert_allclose(res.x, u0 + step, rtol=1e-12)
    assert res.m0_linearized > 0.32  # the grown value (0.3235)
