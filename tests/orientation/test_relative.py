"""Relative orientation: the y-parallax equation, the rigorous model and the solver."""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.orientation import relative as rel

C = 152.7
B = 92.0


def _terrain(rng, n=20, relief=0.1):
    X = rng.uniform(-20, B + 20, n)
    Y = rng.uniform(-100, 100, n)
    Z = -C * (1 + relief * rng.uniform(-0.5, 0.5, n))
    return np.column_stack([X, Y, Z])


def _pair(P, elements, kind="dependent", sequence="opk"):
    st = rel.PairState.from_elements(elements, B, kind, sequence)
    xy1 = ov.project(P, np.zeros(3), ov.matrix_from_opk(*st.angles_left, sequence=sequence), C)
    xy2 = ov.project(P, st.base, ov.matrix_from_opk(*st.angles_right, sequence=sequence), C)
    return xy1, xy2


@pytest.mark.parametrize("kind", ["dependent", "independent"])
def test_linearised_equation_is_the_derivative_of_the_rigorous_parallax(kind):
    # at the normal case the rigorous Jacobian must be exactly −A (a correction d
    # clearing the parallax satisfies p = A d = −J d); rounding only
    P = _terrain(np.random.default_rng(1))
    xy1, xy2 = _pair(P, np.zeros(5), kind)
    p, J = rel.y_parallax_jacobian(xy1, xy2, C, np.zeros(5), B, kind)
    assert np.abs(p).max() < 1e-12
    A = rel.design(P[:, 0], P[:, 1], P[:, 2], B, kind)
    np.testing.assert_allclose(J, -A, atol=1e-10)


def test_linearised_equation_predicts_small_parallaxes():
    # parallaxes of a small true misorientation (10 c) agree with A·(−e) to second order:
    # (1.6e-3 rad)² × ~200 mm ≈ 5e-4 mm
    rng = np.random.default_rng(2)
    P = _terrain(rng)
    e = np.array([0.2, -0.3, 1.5e-3, -1.2e-3, 1.6e-3])
    xy1, xy2 = _pair(P, e)
    p, _ = rel.y_parallax(xy1, xy2, C, rel.PairState.from_elements(np.zeros(5), B))
    _, pts = rel.y_parallax(xy1, xy2, C, rel.PairState.from_elements(np.zeros(5), B))
    A = rel.design_dependent(pts[:, 0], pts[:, 1], pts[:, 2], B)
    # the current state is the normal case, the truth e: the corrections are d = e
    np.testing.assert_allclose(p, A @ e, atol=2e-3)
    # Kovarik's printed equation (signs of bz and κ the other way round) with the
    # same elements does not predict them: the sign conventions matter
    A_k = A * rel.KOVARIK_SIGNS
    assert np.abs(p - A_k @ e).max() > 0.1
    # ... but it does when his elements are counted in his senses
    np.testing.assert_allclose(A_k @ rel.orientviz_to_kovarik(e), p, atol=2e-3)


@pytest.mark.parametrize("kind", ["dependent", "independent"])
@pytest.mark.parametrize("sequence", ["opk", "pok"])
def test_jacobian_against_finite_differences(kind, sequence):
    rng = np.random.default_rng(3)
    P = _terrain(rng)
    e = np.array([0.8, -1.1, 0.03, -0.02, 0.05])
    xy1, xy2 = _pair(P, np.array([0.3, 0.2, -0.01, 0.02, 0.01]), kind, sequence)
    p, J = rel.y_parallax_jacobian(xy1, xy2, C, e, B, kind, sequence)
    h = 1e-6
    for j in range(5):
        ep, em = e.copy(), e.copy()
        ep[j] += h
        em[j] -= h
        fd = (
            rel.y_parallax_jacobian(xy1, xy2, C, ep, B, kind, sequence)[0]
            - rel.y_parallax_jacobian(xy1, xy2, C, em, B, kind, sequence)[0]
        ) / (2 * h)
        # central differences: truncation ~h² × third derivative, rounding ~1e-13/h
        np.testing.assert_allclose(J[:, j], fd, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("kind", ["dependent", "independent"])
def test_noise_free_solution_is_exact(kind):
    rng = np.random.default_rng(4)
    P = _terrain(rng, 12, relief=0.2)
    e = np.array([1.5, -2.0, 0.02, -0.015, 0.01])  # by, bz (mm), ω, φ, κ (rad)
    if kind == "independent":
        e = np.array([0.03, -0.02, 0.02, -0.015, 0.01])  # φ1, κ1, φ2, ω2, κ2 (rad)
    xy1, xy2 = _pair(P, e, kind)
    res = rel.relative_orientation(xy1, xy2, C, kind=kind, b=B)
    assert res.converged
    np.testing.assert_allclose(res.x, e, atol=1e-10)
    assert res.names == list(rel.DEPENDENT if kind == "dependent" else rel.INDEPENDENT)


def test_noisy_solution_within_its_precision():
    # 5 µm image noise; the errors must be consistent with the estimated σ (chi-square)
    rng = np.random.default_rng(5)
    P = _terrain(rng, 40)
    e = np.array([1.0, 0.5, 0.01, 0.02, -0.01])
    xy1, xy2 = _pair(P, e)
    s_img = 0.005
    xy1 = xy1 + rng.normal(0, s_img, xy1.shape)
    xy2 = xy2 + rng.normal(0, s_img, xy2.shape)
    res = rel.relative_orientation(xy1, xy2, C, b=B, sigma=s_img * np.sqrt(2))
    assert res.converged
    err = res.x - e
    chi2 = err @ np.linalg.solve(res.covariance(a_posteriori=False), err)
    assert chi2 < 20.5  # χ²(5) 99.9 % quantile
    assert 0.6 < res.sigma0 < 1.5  # 35 redundant parallaxes: σ0 within ±40 %
    C_ = res.correlations()
    assert C_.shape == (5, 5) and np.allclose(np.diag(C_), 1.0)


def test_fewer_than_five_points():
    P = _terrain(np.random.default_rng(6), 4)
    xy1, xy2 = _pair(P, np.zeros(5))
    with pytest.raises(ov.InputError, match="at least 5 points"):
        rel.relative_orientation(xy1, xy2, C)


def test_zero_base():
    P = _terrain(np.random.default_rng(7), 8)
    xy1 = ov.project(P, np.zeros(3), np.eye(3), C)
    with pytest.raises(ov.InputError, match="zero base"):
        rel.relative_orientation(xy1, xy1.copy(), C)


def test_bad_shapes():
    with pytest.raises(ov.InputError, match="same shape"):
        rel.relative_orientation(np.zeros((6, 2)), np.zeros((7, 2)), C)
    with pytest.raises(ov.InputError, match="kind"):
        rel.relative_orientation(np.zeros((6, 2)), np.zeros((6, 2)), C, kind="both")


def test_all_points_on_one_profile():
    rng = np.random.default_rng(8)
    P = np.column_stack(
        [np.full(9, 30.0), np.linspace(-90, 90, 9), -C * (1 + 0.1 * rng.uniform(-1, 1, 9))]
    )
    xy1, xy2 = _pair(P, np.zeros(5))
    with pytest.raises(ov.NotDeterminableError) as exc:
        rel.relative_orientation(xy1, xy2, C, b=B)
    # X = const: κ acts like by and φ like a combination of bz and ω
    assert {"by", "kappa"} <= set(exc.value.parameters)
    assert "phi" in exc.value.parameters


def test_points_on_the_danger_cylinder():
    # a circular cylinder parallel to the base that contains the base line:
    # Y² + Z² = 2 Y Y0 + 2 Z Z0 makes the ω column a combination of by and bz
    rng = np.random.default_rng(9)
    Y0, Z0 = 20.0, -90.0
    r = np.hypot(Y0, Z0)
    t = rng.uniform(-1.0, 1.0, 15) + np.pi / 2  # lower half, below the base
    Y = Y0 + r * np.cos(t + np.pi)
    Z = Z0 - r * np.sin(t)
    P = np.column_stack([rng.uniform(0, B, 15), Y, Z])
    assert np.allclose(Y**2 + Z**2, 2 * Y * Y0 + 2 * Z * Z0)
    xy1, xy2 = _pair(P, np.zeros(5))
    with pytest.raises(ov.NotDeterminableError) as exc:
        rel.relative_orientation(xy1, xy2, C, b=B)
    assert {"omega", "by", "bz"} <= set(exc.value.parameters)


# --- bad input for every route (item 8 of the issue) ----------------------------------
def _one_profile(seed=8):
    rng = np.random.default_rng(seed)
    return np.column_stack(
        [np.full(9, 30.0), np.linspace(-90, 90, 9), -C * (1 + 0.1 * rng.uniform(-1, 1, 9))]
    )


def test_independent_pair_bad_input_names_elements():
    xy1, xy2 = _pair(_one_profile(), np.zeros(5))
    with pytest.raises(ov.NotDeterminableError) as exc:
        rel.relative_orientation(xy1, xy2, C, b=B, kind="independent")
    assert {"phi1", "kappa1", "phi2", "kappa2"} <= set(exc.value.parameters)
    with pytest.raises(ov.InputError, match="at least 5 points"):
        rel.relative_orientation(xy1[:4], xy2[:4], C, b=B, kind="independent")
    with pytest.raises(ov.InputError, match="zero base"):
        rel.relative_orientation(xy1, xy1.copy(), C, kind="independent")


def test_given_zero_base_is_refused():
    xy1, xy2 = _pair(_terrain(np.random.default_rng(12), 8), np.zeros(5))
    with pytest.raises(ov.InputError, match="zero base"):
        rel.relative_orientation(xy1, xy2, C, b=0.0)


def test_essential_route_one_profile_and_zero_base():
    from orientviz.orientation.essential import essential_route

    xy1, xy2 = _pair(_one_profile(), np.zeros(5))
    for a, b in ((xy1, xy2), (xy1, xy1.copy())):
        with pytest.raises(ov.NotDeterminableError, match="essential matrix") as exc:
            essential_route(a, b, C, b=B)
        assert exc.value.parameters == ["E"]


def test_scheme_solution_on_one_profile_names_elements():
    from orientviz.orientation import schemes as sch

    P = _one_profile()
    A = rel.design_dependent(P[:, 0], P[:, 1], P[:, 2], B)
    with pytest.raises(ov.NotDeterminableError) as exc:
        sch.least_squares_elements(A, np.zeros(9))
    assert {"by", "kappa", "phi"} <= set(exc.value.parameters)


# --- Kovarik's printed signs of bz and κ -------------------------------------------------
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_kovarik_closed_form_with_adopted_signs_clears_a_rigorous_pair(seed):
    """Corrections from the printed 9-point formulas, mapped with KOVARIK_SIGNS, shrink the
    rigorous parallaxes of a misoriented pair ~tenfold; with the printed signs taken as
    orientviz's (no mapping) they do not."""
    from orientviz.orientation import schemes as sch
    from orientviz.units import RHO_C

    rng = np.random.default_rng(seed)
    b, H, k = 220.7, 366.0, 100.0 / 152.7
    s9 = sch.kovarik9()
    Z = -H * (1 + 0.1 * rng.uniform(-0.5, 0.5, 9))
    X, Y, Z = s9.model_points(b, k * H, Z, placement="ratio")
    P = np.column_stack([X, Y, Z])
    # true pair: bz and κ large enough that a sign error shows
    true = np.array([1.0, 2.0, 40.0, -30.0, 50.0]) / np.array([1, 1, RHO_C, RHO_C, RHO_C])
    st = rel.PairState.from_elements(true, b)
    xy1 = ov.project(P, np.zeros(3), np.eye(3), 1.0)
    xy2 = ov.project(P, st.base, ov.matrix_from_opk(*true[2:]), 1.0)
    zero = rel.PairState.from_elements(np.zeros(5), b)
    p0, pts = rel.y_parallax(xy1, xy2, 1.0, zero)
    kov = sch.kovarik_nine_point(p0, pts[:, 2], b, k, convention="kovarik")
    for signs, shrinks in ((rel.KOVARIK_SIGNS, True), (np.ones(5), False)):
        d = kov * signs
        p1, _ = rel.y_parallax(xy1, xy2, 1.0, rel.PairState.from_elements(d, b))
        ratio = np.sqrt(np.mean(p1**2) / np.mean(p0**2))
        assert bool(ratio < 0.1) == shrinks, (signs, ratio)
    # and the mapped corrections approach the true elements
    d = rel.kovarik_to_orientviz(kov)
    assert np.all(np.sign(d) == np.sign(true))
