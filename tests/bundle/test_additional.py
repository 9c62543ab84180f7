"""Additional-parameter sets: orthogonality, physical terms, names, significance, correlations."""

import numpy as np
import pytest

import orientviz as ov
from orientviz.adjust import gauss_newton
from orientviz.bundle import Brown, Ebner12, Gruen44, analyse, ap_set
from orientviz.bundle.model import eo_deformations


def _grid(n, b=92.0):
    g = np.linspace(-b, b, n)
    gx, gy = np.meshgrid(g, g)
    return np.column_stack([gx.ravel(), gy.ravel()])


@pytest.mark.parametrize("aps, n", [(Ebner12(), 3), (Gruen44(), 5)])
def test_orthogonal_on_their_grid_and_to_the_exterior_orientation(aps, n):
    xy = _grid(n)
    A = aps.design(xy).reshape(-1, aps.k)
    G = A.T @ A
    d = np.sqrt(np.diag(G))
    np.testing.assert_allclose(G / np.outer(d, d), np.eye(aps.k), atol=1e-12)
    E = eo_deformations(xy[:, 0] / 92.0, xy[:, 1] / 92.0).reshape(-1, 6)
    assert np.abs(E.T @ A).max() < 1e-15  # mm² scale; values of A are ~1e-3
    assert len(aps.names) == aps.k == {3: 12, 5: 44}[n]


def test_ebner_units_are_micrometres_at_the_base():
    A = Ebner12(b=92.0).design(np.array([[92.0, 0.0]]))
    assert A[0, 0, 0] == pytest.approx(1e-3)  # b1: 1 µm in x at x = b
    assert A[0, 1, 1] == pytest.approx(1e-3)  # b2: 1 µm in y at x = b


def test_brown_principal_distance_term_is_the_exact_derivative():
    rng = np.random.default_rng(2)
    pts = np.column_stack([rng.uniform(-700, 700, 20), rng.uniform(-700, 700, 20), np.zeros(20)])
    X0, R, c = np.array([0.0, 0.0, 1520.0]), np.eye(3), 152.0
    xy = ov.project(pts, X0, R, c)
    dc_um = 20.0
    shift = ov.project(pts, X0, R, c + dc_um * 1e-3) - xy
    A = Brown(c=c).design(xy)
    # x is linear in c, so the column at the *projected* coordinates is exact; the
    # difference of two ~100 mm doubles carries ~1e-14 mm of round-off
    np.testing.assert_allclose(A[:, :, 2] * dc_um, shift, rtol=0, atol=1e-13)


def test_brown_radial_and_decentering_terms():
    b = Brown(r0=100.0)
    xy = np.array([[60.0, 80.0]])  # r = r0
    A = b.design(xy)[0]
    np.testing.assert_allclose(A[:, 3], [0.6e-3, 0.8e-3])  # k1: 1 µm radial at r0
    np.testing.assert_allclose(A[:, 6], [(1 + 2 * 0.36) * 1e-3, 2 * 0.48e-3])  # p1
    np.testing.assert_allclose(A[:, 8], [0.6e-3, 0.0])  # b1 affinity
    assert b.correction(xy, np.eye(10)[3]).shape == (1, 2)


def test_unknown_names_and_bad_input_are_one_line_errors():
    with pytest.raises(ov.InputError, match="unknown additional-parameter set 'foo'; expected one"):
        ap_set("foo")
    assert ap_set("Ebner-12").name == "ebner12" and ap_set("gruen44", b=80.0).b == 80.0
    with pytest.raises(ov.InputError, match="brown"):
        ap_set("brown", bogus=1)
    with pytest.raises(ov.InputError, match=r"\(n, 2\)"):
        Ebner12().design(np.zeros((4, 3)))
    with pytest.raises(ov.InputError, match="expected 12 parameters"):
        Ebner12().correction(np.zeros((1, 2)), np.zeros(3))


def _fit(columns, truth, rng, sigma=0.002):
    """Estimate ap-like parameters of a linear model with a block 'additional'."""
    xy = _grid(7, 110.0)
    A = np.concatenate([c(xy) for c in columns], axis=2).reshape(-1, len(truth))
    l = A @ truth + rng.normal(0, sigma, A.shape[0])
    model = lambda x: (A @ x, A)
    k = len(truth)
    adj = gauss_newton(
        model,
        np.zeros(k),
        l,
        sigma,
        names=[f"a{i}" for i in range(k)],
        groups={"additional": slice(0, k)},
    )
    return adj


def test_significance_of_planted_parameters():
    rng = np.random.default_rng(4)
    truth = np.zeros(12)
    truth[[0, 4]] = [8.0, -6.0]  # µm; σ of the estimates ≈ 0.5 µm here
    adj = _fit([Ebner12().design], truth, rng)
    an = analyse(adj)
    assert an.significant[0] and an.significant[4]
    # 10 zero parameters at 5 %: at most one false alarm expected for this seed
    assert an.significant.sum() <= 3
    assert not an.pairs and "b" not in " ".join(an.warnings)
    assert "significant" in an.table()


def test_over_parameterisation_is_named():
    """Brown's k1 and Ebner-like affinity duplicated: a pair with |ρ| ≈ 1 is reported."""
    rng = np.random.default_rng(5)
    dup = lambda xy: Brown().design(xy)[:, :, [3, 4]]  # k1, k2: strongly correlated on ±110 mm
    adj = _fit([dup], np.array([3.0, 0.0]), rng)
    an = analyse(adj, threshold=0.9)
    assert an.pairs and {an.pairs[0][0], an.pairs[0][1]} == {"a0", "a1"}
    assert "over-parameterised" in an.warnings[0]


def test_analyse_needs_additional_parameters():
    adj = gauss_newton(lambda x: (x, np.eye(2)), [0.0, 0.0], [1.0, 2.0], 1.0)
    with pytest.raises(ov.InputError, match="no additional parameters"):
        analyse(adj)
