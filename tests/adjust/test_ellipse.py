"""Error ellipses: closed form against eigenvalues and simulation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from orientviz.adjust.ellipse import (
    confidence_scale,
    ellipse_outline,
    error_ellipse,
    inside_fraction,
)
from orientviz.errors import InputError


def test_axes_are_square_roots_of_eigenvalues_and_theta_is_the_major_direction():
    rng = np.random.default_rng(5)
    for _ in range(20):
        L = rng.normal(size=(2, 2))
        C = L @ L.T + 0.01 * np.eye(2)
        e = error_ellipse(C)
        w, V = np.linalg.eigh(C)
        assert e.a == pytest.approx(math.sqrt(w[1]), rel=1e-12)
        assert e.b == pytest.approx(math.sqrt(w[0]), rel=1e-12)
        u = np.array([math.cos(e.theta), math.sin(e.theta)])
        assert abs(u @ V[:, 1]) == pytest.approx(1.0, abs=1e-12)


def test_vectorised_and_3d_blocks():
    C = np.array([np.diag([4.0, 1.0, 9.0]), np.diag([1.0, 4.0, 9.0])])
    e = error_ellipse(C)
    np.testing.assert_allclose(e.a, [2.0, 2.0])
    np.testing.assert_allclose(e.b, [1.0, 1.0])
    np.testing.assert_allclose(np.abs(e.theta), [0.0, math.pi / 2])


def test_confidence_scales_match_chi2_quantiles():
    from scipy.stats import chi2

    for p in (0.39346934, 0.9, 0.95, 0.99):
        assert confidence_scale(p) == pytest.approx(math.sqrt(chi2.ppf(p, 2)), rel=1e-9)
        assert confidence_scale(p, dof=1) == pytest.approx(math.sqrt(chi2.ppf(p, 1)), rel=1e-9)
    with pytest.raises(InputError):
        confidence_scale(1.0)


def test_simulated_points_fall_inside_as_often_as_predicted():
    rng = np.random.default_rng(7)
    C = np.array([[4.0, 1.5], [1.5, 1.0]])
    s = rng.multivariate_normal([1.0, 2.0], C, size=20000)
    assert inside_fraction(s, [1.0, 2.0], C) == pytest.approx(1 - math.exp(-0.5), abs=0.01)
    k = confidence_scale(0.95)
    assert inside_fraction(s, [1.0, 2.0], C, k) == pytest.approx(0.95, abs=0.005)
    ring = ellipse_outline([1.0, 2.0], C, k=1.0)
    d = ring - [1.0, 2.0]
    m2 = np.einsum("ni,ij,nj->n", d, np.linalg.inv(C), d)
    np.testing.assert_allclose(m2, 1.0, rtol=1e-9)


def test_bad_shape_is_an_input_error():
    with pytest.raises(InputError, match="shape"):
        error_ellipse(np.ones(3))
