"""The essential-matrix route, cross-checked against OpenCV."""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.orientation import essential as es
from orientviz.orientation import relative as rel

C, B = 152.7, 92.0
TRUE = np.array([1.5, -2.0, 0.03, -0.02, 0.04])  # by, bz (mm), ω, φ, κ (rad)


def _pair(rng, n=60, noise=0.0):
    P = np.column_stack(
        [
            rng.uniform(-10, 100, n),
            rng.uniform(-100, 100, n),
            -C * (1 + 0.2 * rng.uniform(-1, 1, n)),
        ]
    )
    st = rel.PairState.from_elements(TRUE, B)
    xy1 = ov.project(P, np.zeros(3), np.eye(3), C)
    xy2 = ov.project(P, st.base, ov.matrix_from_opk(*TRUE[2:]), C)
    if noise:
        xy1 = xy1 + rng.normal(0, noise, xy1.shape)
        xy2 = xy2 + rng.normal(0, noise, xy2.shape)
    return xy1, xy2, st


def test_noise_free_essential_and_decomposition():
    xy1, xy2, st = _pair(np.random.default_rng(0))
    E = es.eight_point(xy1, xy2, C)
    d1 = np.column_stack([xy1, np.full(len(xy1), -C)])
    d2 = np.column_stack([xy2, np.full(len(xy2), -C)])
    # rays of ~200 mm: the constraint vanishes to rounding
    assert np.abs(np.einsum("ni,ij,nj->n", d1, E, d2)).max() < 1e-8
    E_true = es.essential_from_orientation(ov.matrix_from_opk(*TRUE[2:]), st.base)
    E_true *= np.sqrt(2) / np.linalg.norm(E_true)
    assert min(np.abs(E - E_true).max(), np.abs(E + E_true).max()) < 1e-10
    R, t, n_front = es.select_by_cheirality(E, xy1, xy2, C)
    assert n_front == len(xy1)
    # the other three candidates put points behind an image
    counts = []
    for Rc, tc in es.decompose_essential(E):
        l1, l2 = es.depths(xy1, xy2, C, Rc, tc)
        counts.append(int(np.sum((l1 > 0) & (l2 > 0))))
    assert sorted(counts)[-2] < len(xy1)
    np.testing.assert_allclose(R, ov.matrix_from_opk(*TRUE[2:]), atol=1e-12)
    np.testing.assert_allclose(t, st.base / np.linalg.norm(st.base), atol=1e-12)


def test_route_linear_and_refined_noise_free():
    xy1, xy2, _ = _pair(np.random.default_rng(1))
    res = es.essential_route(xy1, xy2, C, b=B)
    np.testing.assert_allclose(res.linear, TRUE, atol=1e-10)
    np.testing.assert_allclose(res.x, TRUE, atol=1e-10)
    assert res.converged


def test_route_result_is_typed_with_or_without_refinement():
    """Both routes give a RelativeResult: the model points at the elements they return."""
    xy1, xy2, st = _pair(np.random.default_rng(1))
    for refine in (True, False):
        res = es.essential_route(xy1, xy2, C, b=B, refine=refine)
        assert isinstance(res, rel.RelativeResult) and res.n_front == len(xy1)
        assert (res.kind, res.base, res.c) == ("dependent", B, C)
        _, pts = rel.y_parallax(xy1, xy2, C, rel.PairState.from_elements(res.x, B))
        np.testing.assert_allclose(res.points, pts, atol=1e-9)
        np.testing.assert_allclose(res.state.base, st.base, atol=1e-8)


def test_noisy_route_agrees_with_least_squares_from_zero():
    # the refinement converges to the same minimum as the solver started at the normal case
    xy1, xy2, _ = _pair(np.random.default_rng(2), noise=0.005)
    a = es.essential_route(xy1, xy2, C, b=B, sigma=0.005 * np.sqrt(2))
    b = rel.relative_orientation(xy1, xy2, C, b=B, sigma=0.005 * np.sqrt(2))
    np.testing.assert_allclose(a.x, b.x, atol=1e-9)


def test_against_opencv():
    cv2 = pytest.importorskip("cv2")
    rng = np.random.default_rng(3)
    xy1, xy2, st = _pair(rng, n=100, noise=0.003)
    p1 = np.column_stack([xy1[:, 0] / C, -xy1[:, 1] / C])  # OpenCV: y down, z forward
    p2 = np.column_stack([xy2[:, 0] / C, -xy2[:, 1] / C])
    E_cv, _ = cv2.findEssentialMat(p1, p2, focal=1.0, pp=(0.0, 0.0), method=cv2.LMEDS)
    _, R_cv, t_cv, _ = cv2.recoverPose(E_cv, p1, p2, focal=1.0, pp=(0.0, 0.0))
    D = es.D_OPENCV
    R2_cv = D @ R_cv.T @ D
    B_cv = -R2_cv @ (D @ t_cv.ravel())
    ours = es.essential_route(xy1, xy2, C, b=B, refine=False)
    R_ours, t_ours = ours.R_linear, ours.t_linear
    R_true = ov.matrix_from_opk(*TRUE[2:])
    # 3 µm noise on 100 points: rotations to ~1e-4 rad, base direction ~1e-3
    for R, t in ((R_ours, t_ours), (R2_cv, B_cv / np.linalg.norm(B_cv))):
        assert np.abs(R - R_true).max() < 5e-4
        assert np.abs(t - st.base / np.linalg.norm(st.base)).max() < 5e-3
    assert np.abs(R_ours - R2_cv).max() < 5e-4


def test_essential_input_errors():
    with pytest.raises(ov.InputError, match="8 points"):
        es.eight_point(np.zeros((7, 2)), np.zeros((7, 2)), C)
    with pytest.raises(ov.InputError, match="same shape"):
        es.eight_point(np.zeros((9, 2)), np.zeros((8, 2)), C)


def test_five_point_minimal_contains_the_truth():
    # five exact points: the true E is one of the (up to 10) real solutions
    rng = np.random.default_rng(10)
    E_true = None
    for _ in range(5):
        xy1, xy2, st = _pair(rng, n=5)
        E_true = es.essential_from_orientation(ov.matrix_from_opk(*TRUE[2:]), st.base)
        E_true *= np.sqrt(2) / np.linalg.norm(E_true)
        sols = es.five_point(xy1, xy2, C)
        assert 1 <= len(sols) <= 10
        err = min(min(np.abs(E - E_true).max(), np.abs(E + E_true).max()) for E in sols)
        assert err < 1e-9  # rounding through a 10×10 eigenproblem
        for E in sols:  # every solution is an essential matrix fitting the five points
            s = np.linalg.svd(E, compute_uv=False)
            assert s[2] < 1e-9 and abs(s[0] - s[1]) < 1e-9


def test_five_point_route_with_more_points_and_against_opencv():
    cv2 = pytest.importorskip("cv2")
    rng = np.random.default_rng(11)
    xy1, xy2, st = _pair(rng, n=12, noise=0.002)
    E, R, t = es.five_point_route(xy1, xy2, C)
    R_true = ov.matrix_from_opk(*TRUE[2:])
    # 2 µm noise on 12 points: rotation to ~5e-4 rad
    assert np.abs(R - R_true).max() < 2e-3
    p1 = np.column_stack([xy1[:, 0] / C, -xy1[:, 1] / C])
    p2 = np.column_stack([xy2[:, 0] / C, -xy2[:, 1] / C])
    E_cv, _ = cv2.findEssentialMat(p1, p2, focal=1.0, pp=(0.0, 0.0), method=cv2.LMEDS)
    _, R_cv, _, _ = cv2.recoverPose(E_cv, p1, p2, focal=1.0, pp=(0.0, 0.0))
    D = es.D_OPENCV
    assert np.abs(D @ R_cv.T @ D - R).max() < 2e-3
    with pytest.raises(ov.InputError, match="5 points"):
        es.five_point(xy1[:4], xy2[:4], C)


def test_route_with_the_five_point_solver():
    xy1, xy2, _ = _pair(np.random.default_rng(12), n=20)
    res = es.essential_route(xy1, xy2, C, b=B, solver="five")
    np.testing.assert_allclose(res.linear, TRUE, atol=1e-8)
    np.testing.assert_allclose(res.x, TRUE, atol=1e-10)
    with pytest.raises(ov.InputError, match="solver"):
        es.essential_route(xy1, xy2, C, b=B, solver="seven")


def test_large_rotations_in_the_plotter_sequence():
    # 20-25 gon in φ-ω-κ: the essential matrix starts the rigorous model close enough
    rng = np.random.default_rng(5)
    n = 40
    P = np.column_stack(
        [
            rng.uniform(-10, 100, n),
            rng.uniform(-100, 100, n),
            -C * (1 + 0.2 * rng.uniform(-1, 1, n)),
        ]
    )
    e = np.array([10.0, -8.0, 0.3, -0.25, 0.4])
    st = rel.PairState.from_elements(e, B, "dependent", "pok")
    xy1 = ov.project(P, np.zeros(3), np.eye(3), C)
    xy2 = ov.project(P, st.base, ov.matrix_from_opk(*e[2:], sequence="pok"), C)
    res = es.essential_route(xy1, xy2, C, b=B, sequence="pok")
    assert res.converged and res.iterations <= 4
    np.testing.assert_allclose(res.x, e, atol=1e-10)
