"""Point schemes, Kovarik's closed form, influence, precision and the condition equation."""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.errors import InputError, NotDeterminableError
from orientviz.orientation import relative as rel
from orientviz.orientation import schemes as sch

B, Z0, K_RATIO = 220.7, -366.0, 0.655


def _nine(rng, relief):
    s = sch.kovarik9()
    Z = Z0 * (1 + relief * rng.uniform(-0.5, 0.5, 9))
    X, Y, Z = s.model_points(B, K_RATIO * abs(Z0), Z, placement="ratio")
    return s, X, Y, Z


def test_scheme_layouts():
    assert sch.gruber6().n == 6
    nine = sch.kovarik9()
    assert nine.n == 9
    # the first six points of the nine-point scheme are Gruber's
    np.testing.assert_array_equal(nine.u[:6], sch.gruber6().u)
    np.testing.assert_array_equal(nine.v[:6], sch.gruber6().v)
    g = sch.schmid_grid(3)
    assert g.n == 15 and len(set(g.u)) == 3 and len(set(g.v)) == 5
    assert sch.schmid_grid(2).n == 6
    assert sch.get_scheme("schmid5").n == 5 * 9
    with pytest.raises(InputError):
        sch.schmid_grid(1)
    with pytest.raises(InputError):
        sch.get_scheme("nope")


@pytest.mark.parametrize("relief", [0.0, 0.15, 0.3])
def test_kovarik_closed_form_equals_least_squares(relief):
    # with Y/Z = ∓k exactly (Kovarik's assumption) the printed formulas are the
    # least-squares solution for any heights: agreement to rounding
    rng = np.random.default_rng(10)
    s, X, Y, Z = _nine(rng, relief)
    k = abs(Y[2] / Z[2])
    A = rel.design_dependent(X, Y, Z, B)
    p = A @ np.array([0.3, -0.5, 0.01, -0.02, 0.015]) + rng.normal(0, 0.01, 9)
    np.testing.assert_allclose(
        sch.kovarik_nine_point(p, Z, B, k), sch.least_squares_elements(A, p), rtol=1e-9, atol=1e-12
    )
    kov = sch.kovarik_nine_point(p, Z, B, k, convention="kovarik")
    np.testing.assert_allclose(rel.kovarik_to_orientviz(kov), sch.kovarik_nine_point(p, Z, B, k))


def test_kovarik_closed_form_is_approximate_for_plan_placement():
    # points set at plan positions (Y = ±d whatever Z): Y/Z is no longer ±k, the
    # closed form then differs from least squares by an amount of the order of the relief
    rng = np.random.default_rng(11)
    s = sch.kovarik9()
    Z = Z0 * (1 + 0.15 * rng.uniform(-0.5, 0.5, 9))
    X, Y, Z = s.model_points(B, K_RATIO * abs(Z0), Z, placement="plan")
    A = rel.design_dependent(X, Y, Z, B)
    e = np.array([0.3, -0.5, 0.01, -0.02, 0.015])
    d = sch.kovarik_nine_point(A @ e, Z, B, K_RATIO)
    rel_err = np.abs(d - e)[2:] / np.abs(e[2:])
    assert 1e-4 < rel_err.max() < 0.3


def test_influence_flat_terrain_matches_the_paper():
    # Kovarik: dφ depends on the outer profiles only, the middle profile has no
    # influence on dκ; dω contains all profiles. Exact zeros for flat terrain.
    s = sch.kovarik9()
    X, Y, Z = s.model_points(B, K_RATIO * abs(Z0), Z0)
    G = sch.influence(rel.design_dependent(X, Y, Z, B))
    middle = [s.index(n) for n in "789"]
    base_line = [s.index(n) for n in "12"]
    assert np.abs(G[3, middle]).max() < 1e-15  # φ
    assert np.abs(G[3, base_line]).max() < 1e-15  # φ: and not the base line either
    assert np.abs(G[4, middle]).max() < 1e-15  # κ
    assert np.abs(G[2, middle]).min() > 1e-6  # ω: every profile
    # influence reproduces the solution: G A = I (columns up to ~600 mm: rounding ~1e-12)
    np.testing.assert_allclose(G @ rel.design_dependent(X, Y, Z, B), np.eye(5), atol=1e-10)
    # Kovarik's dφ coefficients (1/(2bk)) on points 3, 4, 5, 6 in his senses (φ same sign)
    np.testing.assert_allclose(G[3, [2, 3, 4, 5]], np.array([1, -1, -1, 1]) / (2 * B * K_RATIO))


def test_influence_mountainous_terrain_couples_through_omega():
    # with relief the middle profile enters dφ and dκ through dω (the zK terms)
    rng = np.random.default_rng(12)
    s, X, Y, Z = _nine(rng, 0.15)
    G = sch.influence(rel.design_dependent(X, Y, Z, B))
    assert np.abs(G[3, 6:]).max() > 1e-7


def test_precision_improves_with_points_and_depends_on_scheme():
    s6, _ = sch.scheme_precision("gruber6", B, K_RATIO * abs(Z0), Z0, sigma=0.01)
    s9, _ = sch.scheme_precision("kovarik9", B, K_RATIO * abs(Z0), Z0, sigma=0.01)
    s15, corr = sch.scheme_precision("schmid3", B, K_RATIO * abs(Z0), Z0, sigma=0.01)
    assert np.all(s9 <= s6 + 1e-15) and np.all(s15 <= s9 + 1e-15)
    # the middle profile adds nothing to φ (flat terrain): same σφ for 6 and 9 points
    assert s9[3] == pytest.approx(s6[3], rel=1e-12)
    # ω gains most
    assert s6[2] / s15[2] > s6[3] / s15[3]
    assert np.allclose(np.diag(corr), 1)


def test_flat_condition_equation():
    s = sch.gruber6()
    X, Y, Z = s.model_points(B, K_RATIO * abs(Z0), Z0)
    a = sch.condition_equation(X, Y, Z, B)
    np.testing.assert_allclose(a, [2, -2, -1, 1, -1, 1], atol=1e-12)
    A = rel.design_dependent(X, Y, Z, B)
    p = A @ np.array([0.3, -0.5, 0.01, -0.02, 0.015])
    assert abs(sch.flat_condition(p)) < 1e-12
    p[2] += 0.05  # a reading error of 50 µm at point 3
    assert sch.flat_condition(p) == pytest.approx(-0.05)


def test_general_condition_equation_with_relief():
    rng = np.random.default_rng(13)
    s = sch.gruber6()
    Z = Z0 * (1 + 0.2 * rng.uniform(-0.5, 0.5, 6))
    X, Y, Z = s.model_points(B, K_RATIO * abs(Z0), Z)
    A = rel.design_dependent(X, Y, Z, B)
    p = A @ np.array([0.3, -0.5, 0.01, -0.02, 0.015])
    w, sw = sch.condition_misclosure(p, X, Y, Z, B)
    assert abs(w) < 1e-10 * sw * 1e3
    # the flat-terrain form is violated by a consistent model with relief
    assert abs(sch.flat_condition(p)) > 1e-3
    p[3] += 0.05
    w, sw = sch.condition_misclosure(p, X, Y, Z, B)
    assert abs(w) > 0.04


def test_condition_needs_six_points_and_geometry():
    s = sch.kovarik9()
    X, Y, Z = s.model_points(B, 200, Z0)
    with pytest.raises(InputError, match="6 points"):
        sch.condition_equation(X, Y, Z, B)
    with pytest.raises(InputError):
        sch.flat_condition([1, 2, 3])
    with pytest.raises(NotDeterminableError):
        sch.influence(
            rel.design_dependent(np.zeros(6), np.linspace(-1, 1, 6) * 200, np.full(6, Z0), B)
        )


def test_kovarik_input_errors():
    with pytest.raises(InputError):
        sch.kovarik_nine_point(np.zeros(6), np.zeros(6), B, K_RATIO)


def test_closed_form_equals_least_squares_property():
    # property: for any heights (±40 % relief), k and base the printed formulas are the
    # least-squares solution whenever the edge points lie at Y/Z = ∓k
    hyp = pytest.importorskip("hypothesis")
    st = hyp.strategies

    @hyp.settings(max_examples=40, deadline=None)
    @hyp.given(
        st.lists(st.floats(-0.2, 0.2), min_size=9, max_size=9),
        st.floats(0.3, 1.2),
        st.floats(100.0, 400.0),
        st.lists(st.floats(-1.0, 1.0), min_size=9, max_size=9),
    )
    def check(dz, k, b, p):
        s = sch.kovarik9()
        Z = Z0 * (1 + np.array(dz))
        X = s.u * b
        Y = -s.v * k * Z  # Y/Z = ∓k exactly (upper edge v = +1 at Y > 0)
        A = rel.design_dependent(X, Y, Z, b)
        ls = sch.least_squares_elements(A, np.array(p))
        cf = sch.kovarik_nine_point(np.array(p), Z, b, k)
        scale = np.abs(ls).max() + 1e-12
        assert np.abs(cf - ls).max() < 1e-8 * scale + 1e-12

    check()
