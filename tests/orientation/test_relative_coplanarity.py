"""Relative orientation by the coplanarity condition, next to Kovarik's and collinearity."""

from __future__ import annotations

import json

import numpy as np
import pytest

from orientviz.cli import main
from orientviz.errors import InputError
from orientviz.orientation.relative import (
    METHODS,
    PairState,
    relative_orientation,
    y_parallax,
)
from orientviz.orientation.relative_coplanarity import triple_products
from orientviz.rotation import matrix_from_opk

C = 152.7  # mm, Kovarik's wide-angle camera
#: nine ground points (3 profiles × 3 rows) with ±6 % relief, m
GROUND = np.array(
    [[x, y, z] for x, y, z in zip(
        [0, 0, 0, 460, 460, 460, 920, 920, 920],
        [700, 0, -700, 700, 0, -700, 700, 0, -700],
        [40, -55, 85, -20, 0, 60, 90, -35, -70],
    )], dtype=float,
)  # fmt: skip
LEFT = (np.array([0.0, 0.0, 1500.0]), np.zeros(3))  # the dependent pair's fixed bundle
RIGHT = (np.array([920.0, 25.0, 1490.0]), np.radians([0.6, -0.8, 1.1]))


def _images(X0, angles, ground=GROUND) -> np.ndarray:
    d = (ground - X0) @ matrix_from_opk(*angles, "opk")  # Rᵀ (X − X0) per row
    return -C * d[:, :2] / d[:, 2:]


def _true_elements(b: float) -> np.ndarray:
    """by, bz, ω, φ, κ of the true pair with the base scaled to bx = b."""
    B = RIGHT[0] - LEFT[0]
    return np.concatenate([B[1:] * b / B[0], RIGHT[1]])


@pytest.fixture(scope="module")
def exact():
    return _images(*LEFT), _images(*RIGHT)


@pytest.fixture(scope="module")
def noisy(exact):
    rng = np.random.default_rng(1968)
    return tuple(xy + rng.normal(0.0, 0.003, xy.shape) for xy in exact)


def test_the_three_methods_reach_the_true_orientation(exact):
    xl, xr = exact
    for method in METHODS:
        res = relative_orientation(xl, xr, C, method=method, b="mean")
        assert res.method == method and res.converged
        assert res.redundancy == len(GROUND) - 5
        np.testing.assert_allclose(res.x[:5], _true_elements(res.base), atol=1e-9)


def test_independent_pair_by_coplanarity_equals_parallax(exact):
    xl, xr = exact
    par = relative_orientation(xl, xr, C, kind="independent")
    cop = relative_orientation(xl, xr, C, kind="independent", method="coplanarity")
    assert cop.converged and cop.kind == "independent"
    np.testing.assert_allclose(cop.x, par.x, atol=1e-10)
    # the same relative orientation as the dependent pair (rotation of R in L's frame)
    dep = relative_orientation(xl, xr, C, method="coplanarity")
    s = cop.state
    R_rel = matrix_from_opk(*s.angles_left).T @ matrix_from_opk(*s.angles_right)
    np.testing.assert_allclose(R_rel, matrix_from_opk(*dep.x[2:5]), atol=1e-9)


def test_with_measuring_errors_coplanarity_is_collinearity_and_parallax_is_close(noisy):
    xl, xr = noisy
    res = {m: relative_orientation(xl, xr, C, method=m) for m in METHODS}
    sd = res["collinearity"].std()[:5]
    gap_cop = np.abs(res["coplanarity"].x - res["collinearity"].x[:5]) / sd
    gap_par = np.abs(res["parallax"].x - res["collinearity"].x[:5]) / sd
    # one least-squares problem, linearised at the observations: second-order gap only
    assert gap_cop.max() < 1e-3
    # Kovarik's estimator weighs the same conditions otherwise: a first-order gap
    assert 10 * gap_cop.max() < gap_par.max() < 1.0
    assert res["coplanarity"].sigma0 == pytest.approx(res["collinearity"].sigma0, rel=1e-3)
    assert res["coplanarity"].redundancy == res["collinearity"].redundancy


def test_the_gaps_are_of_the_second_and_the_first_order_in_the_errors(exact):
    """Doubling one pattern of errors: coplanarity − collinearity × 4, parallax − collinearity × 2."""
    rng = np.random.default_rng(29)
    pattern = [rng.normal(0.0, 1.0, xy.shape) for xy in exact]
    gaps = []
    for size in (0.002, 0.004):  # mm
        xl, xr = (xy + size * e for xy, e in zip(exact, pattern))
        res = {m: relative_orientation(xl, xr, C, method=m) for m in METHODS}
        col = res["collinearity"].x[:5]
        gaps.append([np.abs(res[m].x - col).max() for m in ("coplanarity", "parallax")])
    (cop1, par1), (cop2, par2) = gaps
    assert 3.5 < cop2 / cop1 < 4.5
    assert 1.8 < par2 / par1 < 2.2


def test_coplanarity_residuals_are_the_triple_products(noisy):
    xl, xr = noisy
    res = relative_orientation(xl, xr, C, method="coplanarity")
    by, bz, om, ph, ka = res.x
    B = np.array([res.base, by, bz])
    R2 = matrix_from_opk(om, ph, ka, "opk")
    r1 = np.column_stack([xl, np.full(len(xl), -C)]) / C
    r2 = np.column_stack([xr, np.full(len(xr), -C)]) @ R2.T / C
    F = np.linalg.det(np.stack([np.broadcast_to(B, r1.shape), r1, r2], axis=1))
    np.testing.assert_allclose(res.residuals, F, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(
        triple_products(xl, xr, C, B, np.zeros(3), res.x[2:5]), F, rtol=1e-10, atol=1e-14
    )
    assert res.obs_labels[0] == "1/F"
    # σ of each F propagated from image coordinates of one σ (numerical gradient here)
    sigma_image = 0.005 * C / np.mean(np.abs(res.points[:, 2]))
    h = 1e-6
    grad = np.zeros((len(xl), 4))
    for k in range(4):
        a, b = xl.copy(), xr.copy()
        (a if k < 2 else b)[:, k % 2] += h
        grad[:, k] = (triple_products(a, b, C, B, np.zeros(3), res.x[2:5]) - F) / h
    np.testing.assert_allclose(res.sigma_obs, sigma_image * np.linalg.norm(grad, axis=1), rtol=1e-4)


def test_kovariks_parallax_is_the_triple_product_over_a_factor(noisy):
    xl, xr = noisy
    st = PairState.from_elements(_true_elements(92.0), 92.0)
    p, _ = y_parallax(xl, xr, C, st)
    F = triple_products(xl, xr, C, st.base, st.angles_left, st.angles_right)
    r1 = np.column_stack([xl, np.full(len(xl), -C)]) / C
    r2 = np.column_stack([xr, np.full(len(xr), -C)]) @ matrix_from_opk(*st.angles_right).T / C
    np.testing.assert_allclose(p, -F / (r1[:, 2] * r2[:, 0] - r1[:, 0] * r2[:, 2]), rtol=1e-9)


def test_one_history_over_the_reweighting(noisy):
    res = relative_orientation(*noisy, C, method="coplanarity")
    assert [it.index for it in res.history] == list(range(len(res.history)))
    np.testing.assert_array_equal(res.history[-1].x, res.x)
    assert res.iterations >= 2 and "adjustment" in res.reason


def test_an_unknown_method_names_the_three():
    xy = np.zeros((6, 2))
    with pytest.raises(InputError, match="'parallax' or 'collinearity' or 'coplanarity'"):
        relative_orientation(xy, xy, C, method="epipolar")


def test_the_pair_kind_solves_by_coplanarity(tmp_path, capsys, noisy):
    xl, xr = noisy
    doc = {
        "format": "orientviz/1", "kind": "pair", "sequence": "opk", "camera": {"c": C},
        "units": {"length": "mm", "image": "mm", "angle": "gon"},
        "options": {"method": "coplanarity", "base": "mean"},
        "points": [{"id": f"P{j + 1}", "xl": a[0], "yl": a[1], "xr": b[0], "yr": b[1]}
                   for j, (a, b) in enumerate(zip(xl.tolist(), xr.tolist()))],
    }  # fmt: skip
    path = tmp_path / "pair.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    assert main(["solve", str(path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert "coplanarity" in out["method"]
    direct = relative_orientation(xl, xr, C, method="coplanarity", b="mean")
    phi = next(p for p in out["parameters"] if p["name"] == "phi")
    assert phi["value"] == pytest.approx(direct.x[3] * 200 / np.pi, abs=1e-9)
    assert len(out["points"]) == len(GROUND)
    assert main(["solve", str(path)]) == 0
    text = capsys.readouterr().out
    assert "P1/F" in text and "triple product" in text and "points (X Y Z" in text
