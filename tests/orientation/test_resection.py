"""Space resection: Grunert's three-point solution and collinearity least squares."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from single_image_data import C_MM, ground_points, vertical_image

import orientviz as ov
from orientviz.orientation.resection import grunert_distances, resection_closed_form


def test_closed_form_finds_truth_first_with_fourth_point():
    X0, ang, R = vertical_image()
    rng = np.random.default_rng(0)
    X = ground_points(rng, 8)
    xy = ov.project(X, X0, R, C_MM)
    cands = resection_closed_form(xy, X, C_MM)
    assert 1 <= len(cands) <= 4
    np.testing.assert_allclose(cands[0].X0, X0, atol=1e-7)
    np.testing.assert_allclose(cands[0].R, R, atol=1e-10)
    assert cands[0].rms < 1e-9
    assert all(c.rms > 1e-3 for c in cands[1:])  # the others misfit the remaining points


def test_three_points_truth_among_candidates():
    X0, _, R = vertical_image()
    X = ground_points(np.random.default_rng(1), 3)
    cands = resection_closed_form(ov.project(X, X0, R, C_MM), X, C_MM)
    err = [np.linalg.norm(c.X0 - X0) for c in cands]
    assert min(err) < 1e-6
    for c in cands:  # every candidate reproduces the three image points exactly
        np.testing.assert_allclose(
            ov.project(X, c.X0, c.R, C_MM), ov.project(X, X0, R, C_MM), atol=1e-9
        )


def test_grunert_distances_exact():
    rng = np.random.default_rng(2)
    X = ground_points(rng, 3)
    C = np.array([100.0, 50.0, 900.0])
    d = X - C
    sols = grunert_distances(d, X)
    true = np.linalg.norm(d, axis=1)
    assert np.min(np.abs(sols - true).max(axis=1)) < 1e-8


def test_least_squares_noise_free_exact():
    X0, ang, R = vertical_image()
    X = ground_points(np.random.default_rng(3), 10)
    res = ov.resection(ov.project(X, X0, R, C_MM), X, C_MM)
    np.testing.assert_allclose(res.x, np.r_[X0, ang], atol=1e-8)
    assert res.names == ["X0", "Y0", "Z0", "omega", "phi", "kappa"]
    assert res.redundancy == 20 - 6 and res.cofactor.shape == (6, 6)


@pytest.mark.parametrize("sequence", ["opk", "pok"])
def test_least_squares_sequences(sequence):
    X0, _, R = vertical_image()
    X = ground_points(np.random.default_rng(4), 6)
    res = ov.resection(ov.project(X, X0, R, C_MM), X, C_MM, sequence=sequence)
    np.testing.assert_allclose(res.R, R, atol=1e-10)


def test_noisy_precision_and_sigma0():
    # 200 replicas, σ = 5 µm, r = 2·12 − 6 = 18: mean σ̂0² has standard error
    # sqrt(2/(18·200)) ≈ 0.024, bound 0.1 ≈ 4σ; true errors over a-priori σ: |z| < 4.5.
    X0, ang, R = vertical_image()
    rng = np.random.default_rng(5)
    X = ground_points(rng, 12)
    xy = ov.project(X, X0, R, C_MM)
    s02, zmax = [], 0.0
    for _ in range(200):
        res = ov.resection(xy + rng.normal(0, 0.005, xy.shape), X, C_MM, sigma=0.005)
        s02.append(res.sigma0**2)
        zmax = max(zmax, np.max(np.abs(res.x - np.r_[X0, ang]) / res.std(a_posteriori=False)))
    assert abs(np.mean(s02) - 1) < 0.1
    assert zmax < 4.5


def test_correlation_X0_phi_is_high_for_vertical_image():
    # the classic: a shift along X and a tilt φ move the image points almost alike
    X0, _, R = vertical_image()
    X = ground_points(np.random.default_rng(6), 9, relief=20.0)
    res = ov.resection(ov.project(X, X0, R, C_MM), X, C_MM)
    C = res.correlations()
    assert abs(C[res.index("Y0"), res.index("omega")]) > 0.9
    assert abs(C[res.index("X0"), res.index("phi")]) > 0.9


def test_interior_orientation_estimated_with_relief():
    rng = np.random.default_rng(7)
    X = ground_points(rng, 20, relief=400.0)
    cam = ov.FrameCamera(c=150.0, x0=0.01, y0=-0.02)
    X0, ang = np.array([0.0, 0.0, 1200.0]), np.array([0.01, 0.02, 0.3])
    R = ov.matrix_from_opk(*ang)
    xy = ov.project(X, X0, R, cam.c, cam.x0, cam.y0)
    res = ov.resection(xy, X, ov.FrameCamera(c=152.0), interior=True)
    np.testing.assert_allclose(res.x, np.r_[X0, ang, 0.01, -0.02, 150.0], atol=1e-7)
    assert res.camera.c == pytest.approx(150.0)


def test_interior_with_flat_control_is_not_determinable():
    # flat control: c and Z0 (and x0/φ, y0/ω) cannot be separated
    rng = np.random.default_rng(8)
    X = ground_points(rng, 12, relief=0.0)
    X0, R = np.array([0.0, 0.0, 1500.0]), np.eye(3)
    xy = ov.project(X, X0, R, C_MM)
    with pytest.raises(ov.NotDeterminableError) as exc:
        ov.resection(xy, X, C_MM, interior=True, start=(X0, np.zeros(3)))
    assert "c" in exc.value.parameters and "Z0" in exc.value.parameters


@pytest.mark.parametrize("sequence", ["opk", "pok"])
def test_jacobian_against_finite_differences_and_camera(sequence):
    from orientviz.camera import collinearity_jacobian
    from orientviz.orientation.resection import resection_model

    X0, ang, _ = vertical_image()
    X = ground_points(np.random.default_rng(9), 4)
    p = np.r_[X0, ang, 0.01, -0.02, C_MM]
    f0, J = resection_model(p, X, sequence)
    xy, Je, _, Ji = collinearity_jacobian(X, X0, ang, C_MM, 0.01, -0.02, sequence)
    np.testing.assert_allclose(f0, xy.reshape(-1), atol=1e-12)
    np.testing.assert_allclose(J, np.concatenate([Je, Ji], axis=2).reshape(-1, 9), atol=1e-12)
    for k in range(9):
        h = 1e-6 if k in (3, 4, 5) else 1e-3
        dp = np.zeros(9)
        dp[k] = h
        fp = resection_model(p + dp, X, sequence)[0]
        fm = resection_model(p - dp, X, sequence)[0]
        # central differences: truncation ~h^2 f''' is far below 1e-6 of |J| (up to ~200 mm/rad)
        np.testing.assert_allclose(J[:, k], (fp - fm) / (2 * h), rtol=1e-5, atol=1e-7)


def test_bad_input_and_degenerate():
    X0, _, R = vertical_image()
    X = ground_points(np.random.default_rng(10), 5)
    xy = ov.project(X, X0, R, C_MM)
    with pytest.raises(ov.InputError, match="as many"):
        ov.resection(xy[:4], X, C_MM)
    with pytest.raises(ov.InputError, match="shape"):
        ov.resection(xy[:, :1], X, C_MM)
    with pytest.raises(ov.NotDeterminableError, match="at least"):
        ov.resection(xy[:2], X[:2], C_MM)
    line = np.column_stack([np.linspace(-300, 300, 4), np.linspace(-100, 200, 4), np.zeros(4)])
    with pytest.raises(ov.NotDeterminableError, match="collinear"):
        ov.resection(ov.project(line, X0, R, C_MM), line, C_MM)
    with pytest.raises(ov.InputError, match="interior"):
        ov.resection(xy, X, C_MM, interior=("f",))


@settings(max_examples=40, deadline=None)
@given(
    kappa=st.floats(-np.pi, np.pi),
    omega=st.floats(-0.3, 0.3),
    phi=st.floats(-0.3, 0.3),
    seed=st.integers(0, 2**16),
)
def test_property_closed_form_then_ls_recovers_pose(kappa, omega, phi, seed):
    rng = np.random.default_rng(seed)
    X = ground_points(rng, 6)
    X0 = np.array([rng.uniform(-200, 200), rng.uniform(-200, 200), rng.uniform(900, 3000)])
    R = ov.matrix_from_opk(omega, phi, kappa)
    xy = ov.project(X, X0, R, C_MM)
    res = ov.resection(xy, X, C_MM)
    np.testing.assert_allclose(res.R, R, atol=1e-8)
    np.testing.assert_allclose(res.x[:3], X0, atol=1e-5)


def test_only_estimated_interior_parameters_are_reported():
    rng = np.random.default_rng(12)
    X = ground_points(rng, 12, relief=400.0)
    X0, R = np.array([0.0, 0.0, 1200.0]), ov.matrix_from_opk(0.01, 0.02, 0.3)
    xy = ov.project(X, X0, R, 150.0)
    res = ov.resection(xy, X, ov.FrameCamera(c=151.0), interior=("c",))
    assert res.names == ["X0", "Y0", "Z0", "omega", "phi", "kappa", "c"]
    assert res.cofactor.shape == (7, 7) and res.history[-1].x.shape == (7,)
    assert res["c"] == pytest.approx(150.0, abs=1e-8)
    assert res.camera.x0 == 0.0


# --- degenerate input: a clear NotDeterminableError, never numpy's LinAlgError -------------
_X3 = np.array([[0.0, 0.0, 0.0], [100.0, 0.0, 0.0], [0.0, 100.0, 0.0], [100.0, 100.0, 5.0]])


@pytest.mark.parametrize("n", [3, 4])
def test_closed_form_all_image_points_at_one_location(n):
    with pytest.raises(ov.NotDeterminableError, match="1 location") as info:
        resection_closed_form(np.full((n, 2), 3.0), _X3[:n], C_MM)
    assert info.value.parameters[:3] == ["X0", "Y0", "Z0"]


def test_closed_form_two_rays_in_one_direction():
    # used to end in "LinAlgError: SVD did not converge" (found by a random sweep)
    xy = np.array([[50.0, 0.0], [-50.0, -50.0], [0.0, -50.0], [100.0, -50.0], [100.0, -50.0]])
    X = np.array(
        [
            [100.5613032690872, -110.86122162274388, 136.30190619659],
            [-102.49533502280157, -164.83053985345455, 52.034432760912075],
            [236.81270481026667, -66.26434144847433, 93.84521740262728],
            [-111.48443066945354, -35.794518552902815, 154.2464437467255],
            [-31.559010286789267, 64.30568565771242, -69.48535374232124],
        ]
    )
    try:
        cands = resection_closed_form(xy, X, C_MM)
    except ov.NotDeterminableError as exc:
        assert "X0" in exc.parameters
    else:
        assert all(np.all(np.isfinite(c.X0)) for c in cands)
    with pytest.raises(ov.NotDeterminableError, match="same direction"):
        resection_closed_form(xy, X, C_MM, use=(0, 3, 4))


def test_closed_form_collinear_control_points():
    xy = np.array([[0.0, 0.0], [10.0, 0.0], [0.0, 10.0], [10.0, 10.0]])
    X = np.outer([0.0, 1.0, 2.0, 3.0], [100.0, 20.0, 1.0])
    with pytest.raises(ov.NotDeterminableError, match="collinear"):
        resection_closed_form(xy, X, C_MM)


def test_grunert_degenerate_directions():
    with pytest.raises(ov.InputError, match="zero"):
        grunert_distances(np.zeros((3, 3)), _X3[:3])
    d = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, -1.0], [0.1, 0.0, -1.0]])
    with pytest.raises(ov.NotDeterminableError, match="rays 1 and 2"):
        grunert_distances(d, _X3[:3])
    with pytest.raises(ov.InputError, match="finite"):
        grunert_distances(np.full((3, 3), np.nan), _X3[:3])


def test_closed_form_random_degenerate_sweep_raises_only_orientviz_errors():
    """Near-collinear control points, clustered or gridded image points: no LinAlgError."""
    from orientviz.errors import OrientvizError

    rng = np.random.default_rng(11)
    for t in range(400):
        n = int(rng.integers(3, 6))
        X = rng.normal(0, 100, (n, 3))
        xy = rng.normal(0, 50, (n, 2))
        if t % 3 == 0:
            X = np.outer(rng.normal(size=n), rng.normal(size=3)) + rng.normal(0, 1e-9, (n, 3))
        elif t % 3 == 1:
            xy = xy[0] + rng.normal(0, 1e-10, (n, 2))
        else:
            xy = np.round(xy / 50) * 50
        try:
            resection_closed_form(xy, X, C_MM)
        except OrientvizError:
            pass
