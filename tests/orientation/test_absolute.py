"""3D similarity / rigid transformation: closed form and least squares."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import orientviz as ov
from orientviz.orientation.absolute import (
    SimilarityTransform,
    similarity_closed_form,
    similarity_model,
)

TRUE = np.array([5000.0, 3000.0, 420.0, ov.to_rad(1.2), ov.to_rad(-2.5), ov.to_rad(137.0), 12.5])


def model_points(rng, n=8):
    # a model about 200 x 200 units with ±20 units of relief
    return np.column_stack(
        [rng.uniform(-100, 100, n), rng.uniform(-100, 100, n), rng.uniform(-20, 20, n)]
    )


@pytest.mark.parametrize("sequence", ["opk", "pok"])
def test_noise_free_exact(sequence):
    rng = np.random.default_rng(0)
    x = model_points(rng)
    tf = SimilarityTransform.from_params(TRUE, sequence)
    X = tf.apply(x)
    cf = similarity_closed_form(x, X)
    np.testing.assert_allclose(cf.R, tf.R, atol=1e-12)
    np.testing.assert_allclose(cf.scale, tf.scale, rtol=1e-12)
    np.testing.assert_allclose(cf.t, tf.t, atol=1e-8)
    res = ov.similarity_transform(x, X, sequence=sequence)
    np.testing.assert_allclose(res.x, TRUE, atol=1e-9)
    assert res.converged and res.redundancy == 3 * 8 - 7
    assert np.abs(res.residuals).max() < 1e-8


def test_rigid_noise_free_exact():
    rng = np.random.default_rng(1)
    x = model_points(rng)
    p = TRUE.copy()
    p[6] = 1.0
    tf = SimilarityTransform.from_params(p)
    X = tf.apply(x)
    cf = similarity_closed_form(x, X, scale=False)
    assert cf.scale == 1.0
    np.testing.assert_allclose(cf.R, tf.R, atol=1e-12)
    res = ov.similarity_transform(x, X, rigid=True)
    np.testing.assert_allclose(res.x, p, atol=1e-9)
    assert res.redundancy == 24 - 6
    assert res.std()[6] == 0.0  # scale held fixed


def test_apply_inverse_roundtrip():
    rng = np.random.default_rng(2)
    x = model_points(rng)
    tf = SimilarityTransform.from_params(TRUE)
    np.testing.assert_allclose(tf.inverse().apply(tf.apply(x)), x, atol=1e-10)
    np.testing.assert_allclose(tf.apply(x[0]), tf.apply(x)[0])


def test_closed_form_never_reflects():
    rng = np.random.default_rng(3)
    x = model_points(rng)
    X = x * np.array([1.0, -1.0, 1.0])  # a mirror image: no rotation can fit it
    cf = similarity_closed_form(x, X)
    assert np.isclose(np.linalg.det(cf.R), 1.0)


def test_closed_form_weights_ignore_zero_weight_outlier():
    rng = np.random.default_rng(4)
    x = model_points(rng)
    tf = SimilarityTransform.from_params(TRUE)
    X = tf.apply(x)
    X[0] += 50.0
    w = np.ones(len(x))
    w[0] = 0.0
    cf = similarity_closed_form(x, X, w)
    np.testing.assert_allclose(cf.params(), TRUE, atol=1e-9)


def test_closed_form_equals_least_squares_for_equal_weights():
    # With full control and equal isotropic weights the SVD solution *is* the
    # least-squares minimiser, so both must agree to the iteration tolerance.
    rng = np.random.default_rng(5)
    x = model_points(rng, 12)
    X = SimilarityTransform.from_params(TRUE).apply(x) + rng.normal(0, 0.05, (12, 3))
    cf = similarity_closed_form(x, X)
    res = ov.similarity_transform(x, X, sigma_target=0.05)
    # tolerance: 1e-6 of the parameters' σ (the engine's stopping rule)
    np.testing.assert_allclose(res.x, cf.params(), atol=1e-6 * res.std().max())


def test_noisy_within_precision_and_sigma0_statistics():
    # 300 replicas with σ = 2 cm: the mean of σ̂0² estimates 1 with a standard error
    # of sqrt(2/(r·N)) = sqrt(2/(17·300)) ≈ 0.02, so |mean − 1| < 0.1 is a 5σ bound;
    # the true errors normalised by the estimated σ are ~N(0,1): |z| < 4.5 in all.
    rng = np.random.default_rng(6)
    x = model_points(rng)
    X = SimilarityTransform.from_params(TRUE).apply(x)
    s02, zmax = [], 0.0
    for _ in range(300):
        res = ov.similarity_transform(x, X + rng.normal(0, 0.02, X.shape), sigma_target=0.02)
        s02.append(res.sigma0**2)
        zmax = max(zmax, np.max(np.abs(res.x - TRUE) / res.std(a_posteriori=False)))
    assert abs(np.mean(s02) - 1.0) < 0.1
    assert zmax < 4.5


def test_jacobian_matches_finite_differences():
    rng = np.random.default_rng(7)
    x = model_points(rng, 5)
    for seq in ("opk", "pok"):
        f0, J = similarity_model(TRUE, x, seq)
        h = 1e-6
        for k in range(7):
            dp = np.zeros(7)
            dp[k] = h
            fd = (
                similarity_model(TRUE + dp, x, seq)[0] - similarity_model(TRUE - dp, x, seq)[0]
            ) / (2 * h)
            # central differences: error ~ h² · f''' ≈ 1e-12 · 1e4 → 1e-6 relative to |J| ~ 1e3
            np.testing.assert_allclose(J[:, :, k], fd, rtol=1e-6, atol=1e-5)


def test_partial_control_height_and_planimetry():
    rng = np.random.default_rng(8)
    x = model_points(rng, 6)
    X = SimilarityTransform.from_params(TRUE).apply(x)
    Xp = X.copy()
    Xp[2:4, :2] = np.nan  # height-only points
    Xp[4:6, 2] = np.nan  # planimetry-only points
    res = ov.similarity_transform(x, Xp)
    np.testing.assert_allclose(res.x, TRUE, atol=1e-8)
    assert res.redundancy == 6 + 2 + 4 - 7
    assert np.isnan(res.residuals_xyz[2, 0])
    assert res.used.sum() == 12


def test_minimal_classic_layout_two_full_one_height():
    # 2 full points + 1 height point = 7 coordinates: the classic minimum, redundancy 0
    rng = np.random.default_rng(9)
    x = model_points(rng, 3)
    X = SimilarityTransform.from_params(TRUE).apply(x)
    X[2, :2] = np.nan
    res = ov.similarity_transform(x, X)
    assert res.redundancy == 0
    np.testing.assert_allclose(res.x, TRUE, atol=1e-8)


def test_sigma_source_tiny_equals_classic():
    rng = np.random.default_rng(10)
    x = model_points(rng)
    X = SimilarityTransform.from_params(TRUE).apply(x) + rng.normal(0, 0.02, (8, 3))
    classic = ov.similarity_transform(x, X, sigma_target=0.02)
    both = ov.similarity_transform(x, X, sigma_target=0.02, sigma_source=1e-7)
    # model σ 1e-7 units ≈ 1.25e-6 m after scaling, 1e-4 of the control σ: agreement to ~1e-4 σ
    np.testing.assert_allclose(both.x[:7], classic.x, atol=1e-3 * classic.std().max())
    assert both.n_unknowns == 7 + 24 and both.redundancy == classic.redundancy


def test_sigma_source_noisy_model_sigma0():
    # noise in both sets, both weighted correctly: mean σ̂0² ≈ 1 (standard error ≈ 0.035
    # for r = 17, 100 replicas; bound 0.15 ≈ 4σ)
    rng = np.random.default_rng(11)
    x = model_points(rng)
    X = SimilarityTransform.from_params(TRUE).apply(x)
    s02 = []
    for _ in range(100):
        xn = x + rng.normal(0, 0.002, x.shape)  # model units; × 12.5 = 2.5 cm
        Xn = X + rng.normal(0, 0.02, X.shape)
        s02.append(
            ov.similarity_transform(xn, Xn, sigma_target=0.02, sigma_source=0.002).sigma0 ** 2
        )
    assert abs(np.mean(s02) - 1.0) < 0.15


def test_bad_input_and_degenerate():
    rng = np.random.default_rng(12)
    x = model_points(rng, 5)
    X = SimilarityTransform.from_params(TRUE).apply(x)
    with pytest.raises(ov.InputError, match="expected shape"):
        ov.similarity_transform(x[:, :2], X)
    with pytest.raises(ov.InputError, match="like the source"):
        similarity_closed_form(x, X[:4])
    with pytest.raises(ov.InputError, match="σ > 0"):
        ov.similarity_transform(x, X, sigma_target=0.0)
    with pytest.raises(ov.NotDeterminableError, match="at least 3"):
        similarity_closed_form(x[:2], X[:2])
    line = np.outer(np.arange(5.0), [1.0, 2.0, 0.5])
    with pytest.raises(ov.NotDeterminableError, match="collinear"):
        similarity_closed_form(line, SimilarityTransform.from_params(TRUE).apply(line))
    with pytest.raises(ov.NotDeterminableError) as exc:
        ov.similarity_transform(line, SimilarityTransform.from_params(TRUE).apply(line))
    assert exc.value.parameters
    with pytest.raises(ov.NotDeterminableError, match="at least 7 control coordinates"):
        ov.similarity_transform(x, np.where([[True, True, False]], np.nan, X))  # 5 heights
    x8 = model_points(rng, 8)
    only_heights = SimilarityTransform.from_params(TRUE).apply(x8)
    only_heights[:, :2] = np.nan
    with pytest.raises(ov.NotDeterminableError, match="planimetric"):
        ov.similarity_transform(x8, only_heights)


angles = st.floats(-np.pi, np.pi, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(
    omega=angles,
    phi=st.floats(-1.5, 1.5),
    kappa=st.one_of(angles, st.floats(np.pi - 1e-3, np.pi), st.floats(-np.pi, -np.pi + 1e-3)),
    scale=st.floats(0.01, 100.0),
    seed=st.integers(0, 2**16),
)
def test_property_recovers_any_transform(omega, phi, kappa, scale, seed):
    rng = np.random.default_rng(seed)
    x = model_points(rng, 6)
    R = ov.matrix_from_opk(omega, phi, kappa)
    t = rng.uniform(-1e4, 1e4, 3)
    X = t + scale * x @ R.T
    cf = similarity_closed_form(x, X)
    np.testing.assert_allclose(cf.R, R, atol=1e-9)
    np.testing.assert_allclose(cf.scale, scale, rtol=1e-9)
    np.testing.assert_allclose(cf.apply(x), X, atol=1e-7 * (1 + scale * 100))
    res = ov.similarity_transform(x, X, sigma_target=0.01)
    np.testing.assert_allclose(res.transform.R, R, atol=1e-9)


@pytest.mark.parametrize("tilt_gon", [10.0, 40.0])
def test_partial_control_start_converges_for_tilted_models(tilt_gon):
    # the planimetric start assumes ω = φ = 0; Gauss-Newton must still reach the truth
    rng = np.random.default_rng(13)
    x = model_points(rng)
    p = np.array([1000.0, 2000.0, 300.0, ov.to_rad(tilt_gon), ov.to_rad(-tilt_gon), 2.0, 5.0])
    X = SimilarityTransform.from_params(p).apply(x)
    X[:4, 2] = np.nan
    X[4:, :2] = np.nan
    res = ov.similarity_transform(x, X)
    assert res.converged
    np.testing.assert_allclose(res.x, p, atol=1e-9)


def test_gimbal_lock_is_reported_and_other_sequence_works():
    # φ = 100 gon in ω-φ-κ: ω and κ turn about the same axis, only their sum counts
    rng = np.random.default_rng(14)
    x = model_points(rng)
    p = np.array([1000.0, 2000.0, 300.0, 0.3, np.pi / 2, 0.2, 5.0])
    X = SimilarityTransform.from_params(p).apply(x)
    with pytest.raises(ov.NotDeterminableError) as exc:
        ov.similarity_transform(x, X, sequence="opk")
    assert set(exc.value.parameters) == {"omega", "kappa"}
    res = ov.similarity_transform(x, X, sequence="pok")
    np.testing.assert_allclose(res.transform.R, SimilarityTransform.from_params(p).R, atol=1e-12)
