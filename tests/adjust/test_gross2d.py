"""2-D outlier test of image points: hand-computed values, vᵀPv decrease, B-method levels."""

import numpy as np
import pytest
from scipy.special import chdtrc, chndtr

from orientviz.adjust.gross import noncentrality
from orientviz.adjust.gross2d import (
    critical_values_2d,
    level_2d,
    noncentrality_2d,
    statistic_2d,
)
from orientviz.adjust.snooping import data_snooping
from orientviz.errors import InputError


def test_hand_computed_full_rank():
    # z = (2, 1), R = [[0.5, 0.1], [0.1, 0.4]]: det = 0.19,
    # T = (0.4·4 − 2·0.1·2·1 + 0.5·1) / 0.19 = 1.7 / 0.19
    T, dof = statistic_2d([[2.0, 1.0]], [[0.5, 0.4]], [0.1])
    assert dof.tolist() == [2]
    assert T[0] == pytest.approx(1.7 / 0.19, rel=1e-12)
    # uncorrelated: T = w_x² + w_y² (w = z / √r)
    T, _ = statistic_2d([[2.0, 1.0]], [[0.5, 0.4]], [0.0])
    assert T[0] == pytest.approx(4 / 0.5 + 1 / 0.4, rel=1e-12)


def test_hand_computed_rank_one():
    # a 2-ray point: no redundancy in x, r_y = 0.5 → T = z_y² / 0.5 with 1 dof
    T, dof = statistic_2d([[0.0, 1.5]], [[0.0, 0.5]], [0.0])
    assert dof.tolist() == [1] and T[0] == pytest.approx(4.5, rel=1e-12)
    # the same, rotated: R = 0.5 u uᵀ with u = (0.6, 0.8); z = 2u → T = (uᵀz)² / 0.5 = 8
    u = np.array([0.6, 0.8])
    R = 0.5 * np.outer(u, u)
    T, dof = statistic_2d([2 * u], [[R[0, 0], R[1, 1]]], [R[0, 1]])
    assert dof.tolist() == [1] and T[0] == pytest.approx(8.0, rel=1e-9)
    # nothing testable
    T, dof = statistic_2d([[1.0, 1.0]], [[0.0, 0.001]], [0.0])
    assert dof.tolist() == [0] and T[0] == 0.0


def test_statistic_is_the_decrease_of_vtpv_when_the_pair_is_left_out():
    """Linear model with 8 (x, y) pairs and 5 unknowns: T of a pair = Ω − Ω without it."""
    rng = np.random.default_rng(3)
    n, u = 16, 5
    A = rng.normal(size=(n, u))
    sigma = rng.uniform(0.5, 2.0, n)
    l = A @ rng.normal(size=u) + sigma * rng.normal(size=n)
    l[6] += 8 * sigma[6]  # a blunder in pair 3 (x)

    def fit(rows):
        Aw = A[rows] / sigma[rows, None]
        lw = l[rows] / sigma[rows]
        x = np.linalg.lstsq(Aw, lw, rcond=None)[0]
        return x, float(np.sum((lw - Aw @ x) ** 2))

    x, omega = fit(np.arange(n))
    Aw = A / sigma[:, None]
    R = np.eye(n) - Aw @ np.linalg.inv(Aw.T @ Aw) @ Aw.T  # P½ Q_vv P½
    z = (A @ x - l) / sigma
    r = np.diag(R).reshape(-1, 2)
    rxy = R[0::2, 1::2].diagonal()
    T, dof = statistic_2d(z.reshape(-1, 2), r, rxy)
    assert (dof == 2).all()
    for k in range(n // 2):
        keep = np.setdiff1d(np.arange(n), [2 * k, 2 * k + 1])
        assert T[k] == pytest.approx(omega - fit(keep)[1], rel=1e-9)
    assert int(np.argmax(T)) == 3
    # the non-centrality of a bias is T of the bias alone (noise-free residuals)
    bias = np.zeros(n)
    bias[6:8] = [3.0, -1.0]
    zb = -(R @ (bias / sigma))
    lam = noncentrality_2d(bias.reshape(-1, 2)[3:4], sigma.reshape(-1, 2)[3:4], r[3:4], rxy[3:4])
    Tb, _ = statistic_2d(zb.reshape(-1, 2)[3:4], r[3:4], rxy[3:4])
    assert lam[0] == pytest.approx(Tb[0], rel=1e-9)


def test_b_method_critical_values():
    crit = critical_values_2d(0.001, 0.80)
    lam0 = noncentrality(0.001, 0.80) ** 2
    assert crit[1] == pytest.approx(3.2905**2, rel=1e-4)
    # same power β0 = 80 % at the same non-centrality λ0, for 1 and 2 dof
    assert 1 - chndtr(crit[2], 2, lam0) == pytest.approx(0.80, abs=1e-9)
    assert 1 - chndtr(crit[1], 1, lam0) == pytest.approx(0.80, abs=2e-3)
    assert level_2d() == pytest.approx(chdtrc(2, crit[2]))
    assert 0.001 < level_2d() < 0.005


def test_snooping_2d_needs_pairs_and_the_off_diagonal():
    with pytest.raises(InputError, match="pairs"):
        data_snooping(lambda w: None, 5, test="2d")
    with pytest.raises(InputError, match="unknown test"):
        data_snooping(lambda w: None, 4, test="3d")
