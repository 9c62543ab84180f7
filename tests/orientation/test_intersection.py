"""Forward intersection: many points at once, and one point on the engine."""

from __future__ import annotations

import numpy as np
import pytest
from single_image_data import C_MM, ground_points

import orientviz as ov
from orientviz.orientation.intersection import forward_intersection


def three_images(rng):
    X0 = np.array([[-300.0, 0, 1500], [300, 0, 1500], [0, 250, 1520]])
    ang = rng.normal(0, 0.02, (3, 3))
    return X0, ov.matrix_from_opk(ang[:, 0], ang[:, 1], ang[:, 2])


def observe(X, X0, R):
    p, m = X.shape[0], X0.shape[0]
    img, pt = np.repeat(np.arange(m), p), np.tile(np.arange(p), m)
    return ov.project(X[pt], X0[img], R[img], C_MM), img, pt


def test_noise_free_exact_many_points():
    rng = np.random.default_rng(0)
    X0, R = three_images(rng)
    X = ground_points(rng, 500)
    xy, img, pt = observe(X, X0, R)
    res = ov.intersect_points(xy, img, pt, X0, R, C_MM)
    np.testing.assert_allclose(res.xyz, X, atol=1e-8)
    assert res.converged and np.all(res.redundancy == 3) and np.all(res.n_rays == 3)
    lin = ov.intersect_points(xy, img, pt, X0, R, C_MM, rigorous=False)
    np.testing.assert_allclose(lin.xyz, X, atol=1e-8)  # exact rays meet in one point


def test_noisy_precision_matches_errors():
    # 2000 points, σ = 5 µm: true errors / a-priori σ should have unit spread
    # (standard error of a std from 2000 samples ≈ 1.6 %, bound ±8 %), and the pooled
    # σ̂0² ≈ 1 (standard error sqrt(2/6000) ≈ 1.8 %, bound ±8 %).
    rng = np.random.default_rng(1)
    X0, R = three_images(rng)
    X = ground_points(rng, 2000)
    xy, img, pt = observe(X, X0, R)
    res = ov.intersect_points(xy + rng.normal(0, 0.005, xy.shape), img, pt, X0, R, C_MM)
    z = (res.xyz - X) / res.std()
    assert np.all(np.abs(z.std(axis=0) - 1) < 0.08)
    pooled = np.sum(res.sigma0**2 * res.redundancy) / res.redundancy.sum()
    assert abs(pooled - 1) < 0.08


def test_matches_engine_single_point():
    rng = np.random.default_rng(2)
    X0, R = three_images(rng)
    X = ground_points(rng, 4)
    xy, img, pt = observe(X, X0, R)
    xy = xy + rng.normal(0, 0.005, xy.shape)
    many = ov.intersect_points(xy, img, pt, X0, R, C_MM)
    for k in range(4):
        one = forward_intersection(xy[pt == k], X0, R, C_MM)
        # both minimise the same vᵀPv; agreement to the engine's stopping rule (1e-6 σ)
        np.testing.assert_allclose(one.x, many.xyz[k], atol=1e-5 * one.std().max())
        np.testing.assert_allclose(one.cofactor, many.cofactor[k], rtol=1e-6)
        assert one.sigma0 == pytest.approx(many.sigma0[k], rel=1e-5)


def test_height_precision_grows_with_smaller_base():
    # normal case: σ_Z ≈ (H/B)·(H/c)·σ_x' — halving the base doubles σ_Z
    X = np.array([[0.0, 0.0, 0.0]])
    out = []
    for base in (600.0, 300.0):
        X0 = np.array([[-base / 2, 0, 1500.0], [base / 2, 0, 1500.0]])
        R = np.stack([np.eye(3), np.eye(3)])
        xy, img, pt = observe(X, X0, R)
        out.append(ov.intersect_points(xy, img, pt, X0, R, C_MM).std()[0, 2])
    assert out[1] / out[0] == pytest.approx(2.0, rel=0.02)
    # σ_Z = (H/B)·(H/c)·σ_px with σ_px = √2·σ_x; H/c in m per mm, σ_x in mm → m
    expected = 1500 / 600 * 1500 / C_MM * 0.005 * np.sqrt(2)
    assert out[0] == pytest.approx(expected, rel=0.02)


def test_jacobian_against_finite_differences():
    from orientviz.orientation.intersection import _point_jacobian

    rng = np.random.default_rng(4)
    X0, R = three_images(rng)
    X = ground_points(rng, 3)
    img = np.arange(3)
    args = (X0[img], R[img], np.full(3, C_MM), np.zeros(3), np.zeros(3))
    _, J = _point_jacobian(X, *args)
    h = 1e-3
    for k in range(3):
        d = np.zeros(3)
        d[k] = h
        fd = (_point_jacobian(X + d, *args)[0] - _point_jacobian(X - d, *args)[0]) / (2 * h)
        # truncation h²·f''' ~ 1e-6 · c/H³ · ... negligible against 1e-9 mm/m
        np.testing.assert_allclose(J[:, :, k], fd, atol=1e-9)


def test_degenerate_and_bad_input():
    rng = np.random.default_rng(5)
    X0, R = three_images(rng)
    X = ground_points(rng, 3)
    xy, img, pt = observe(X, X0, R)
    keep = ~((pt == 1) & (img > 0))  # point 1 seen only once
    with pytest.raises(ov.NotDeterminableError, match="fewer than 2 rays for point"):
        ov.intersect_points(xy[keep], img[keep], pt[keep], X0, R, C_MM)
    nanres = ov.intersect_points(xy[keep], img[keep], pt[keep], X0, R, C_MM, on_degenerate="nan")
    assert np.isnan(nanres.xyz[1]).all() and np.isfinite(nanres.xyz[[0, 2]]).all()
    # parallel rays: the same ray from two places along it
    Xc = np.array([[0.0, 0.0, 1500.0], [0.0, 0.0, 1000.0]])
    Rr = np.stack([np.eye(3)] * 2)
    with pytest.raises(ov.NotDeterminableError, match="parallel"):
        forward_intersection(np.zeros((2, 2)), Xc, Rr, C_MM)
    with pytest.raises(ov.NotDeterminableError, match="at least 2"):
        forward_intersection(np.zeros((1, 2)), Xc[:1], Rr[:1], C_MM)
    with pytest.raises(ov.InputError):
        ov.intersect_points(xy, img, pt, X0, R[:2], C_MM)
    with pytest.raises(ov.InputError):
        ov.intersect_points(xy, img + 5, pt, X0, R, C_MM)


def test_symmetric_3x3_helpers_match_numpy():
    from orientviz.orientation.intersection import (
        _sym_full,
        _sym_inverse,
        _sym_outer,
    )

    rng = np.random.default_rng(6)
    M = rng.normal(size=(200, 3, 3))
    S_full = M @ np.swapaxes(M, 1, 2) + 1e-3 * np.eye(3)
    S = S_full[:, [0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]]
    np.testing.assert_allclose(_sym_full(S), S_full)
    inv, det = _sym_inverse(S)
    np.testing.assert_allclose(det, np.linalg.det(S_full), rtol=1e-8, atol=1e-10)
    # inverse of matrices with condition up to ~1e5: agreement to ~1e-8 relative
    np.testing.assert_allclose(_sym_full(inv), np.linalg.inv(S_full), rtol=1e-7, atol=1e-7)
    d = np.array([[0.0, 0.6, 0.8]])
    np.testing.assert_allclose(_sym_outer(d, d), [[0.0, 0.36, 0.64, 0.0, 0.0, 0.48]])


def test_input_checks_of_indices_and_sigma():
    rng = np.random.default_rng(7)
    X0, R = three_images(rng)
    X = ground_points(rng, 3)
    xy, img, pt = observe(X, X0, R)
    with pytest.raises(ov.InputError, match="n_points"):
        ov.intersect_points(xy, img, pt, X0, R, C_MM, n_points=2)
    with pytest.raises(ov.InputError, match="sigma"):
        ov.intersect_points(xy, img, pt, X0, R, C_MM, sigma=0.0)
    # unobserved extra points are reported, or NaN on request
    res = ov.intersect_points(xy, img, pt, X0, R, C_MM, n_points=5, on_degenerate="nan")
    assert res.determinable.tolist() == [True, True, True, False, False]
