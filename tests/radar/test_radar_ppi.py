"""Geometry of the PPI image: mapping (4a), back-projection (4b, 4c), derivatives."""

import numpy as np
import pytest

import orientviz as ov
from orientviz.radar import geier1973 as G
from orientviz.radar.ppi import (
    PARAMS,
    RadarImage,
    back_project,
    horizontal_range,
    plane_normal,
    project,
    project_with_jacobian,
    projection_circle,
    sphere_radius,
)


@pytest.fixture(params=[1, 2, 3])
def image(request):
    return G.images()[request.param]


def test_radial_distance_is_scaled_horizontal_range(image):
    P = G.points("fig7")
    xy = project(P, image)
    r = np.linalg.norm(xy - [image.x0, image.y0], axis=1)
    np.testing.assert_allclose(r, image.m * horizontal_range(P, image), rtol=1e-14)


def test_normal_case_azimuth_is_plane_azimuth():
    # vertical axis, κ = 0: the image is a plan with ranges reduced radially
    im = RadarImage(0.0, 0.0, 1000.0, 1.0, (0.0, 0.0, 0.0))
    P = np.array([[3000.0, 4000.0, -2000.0]])
    xy = project(P, im)
    se = np.sqrt(25e6 + 4e6 - 1e6)
    np.testing.assert_allclose(xy[0], [3000 * se / 5000, 4000 * se / 5000], rtol=1e-14)


def test_back_projection_returns_the_point(image):
    P = G.points("sphere150_convex")
    xy = project(P, image)
    np.testing.assert_allclose(sphere_radius(xy, image), np.linalg.norm(P - image.X0, axis=1))
    n = plane_normal(xy, image)
    np.testing.assert_allclose(np.einsum("ij,ij->i", P - image.X0, n), 0.0, atol=1e-8)
    d = P - image.X0
    el = np.arcsin(d @ image.axis / np.linalg.norm(d, axis=1))
    np.testing.assert_allclose(back_project(xy, image, el), P, atol=1e-7)
    _, r, poly = projection_circle(xy, image, 13)
    np.testing.assert_allclose(
        np.linalg.norm(poly - image.X0, axis=2), r[:, None] + 0 * poly[..., 0]
    )


@pytest.mark.parametrize("sequence", ["pok", "opk"])
def test_jacobian_matches_central_differences(sequence):
    im = G.images(sequence)[3]
    P = G.points("fig7")
    _, J, JP = project_with_jacobian(P, im)
    p0 = im.vector()
    steps = np.array([1e-3, 1e-3, 1e-3, 1e-7, 1e-3, 1e-3, 1e-3, 1e-7, 1e-7, 1e-7])
    for k in range(10):
        dp = np.zeros(10)
        dp[k] = steps[k]
        fp = project(P, RadarImage.from_vector(p0 + dp, sequence))
        fm = project(P, RadarImage.from_vector(p0 - dp, sequence))
        num = (fp - fm) / (2 * steps[k])
        # central differences: truncation ~ step²·f''' (relative 1e-6), cancellation
        # ~ ε·|xy|/step with |xy| ≤ 1e5 m: 10·2.2e-16·1e5/step absolute
        atol = 10 * 2.2e-16 * 1e5 / steps[k]
        np.testing.assert_allclose(J[:, :, k], num, rtol=1e-6, atol=atol, err_msg=PARAMS[k])
    for c in range(3):
        d = np.zeros(3)
        d[c] = 1e-3
        num = (project(P + d, im) - project(P - d, im)) / 2e-3
        np.testing.assert_allclose(JP[:, :, c], num, rtol=1e-6, atol=1e-7)


def test_bad_input_is_one_line():
    im = G.images()[1]
    with pytest.raises(ov.InputError, match="shape"):
        project(np.zeros((3, 2)), im)
    with pytest.raises(ov.InputError, match="closer to the station"):
        project([[10.0, 0.0, -10.0]], im)
    with pytest.raises(ov.InputError, match="rotation axis"):
        project([[0.0, 0.0, -20000.0]], im)
    with pytest.raises(ov.InputError, match="10 radar parameters"):
        RadarImage.from_vector(np.zeros(9))
