import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import orientviz as ov
from orientviz.rotation import (
    check_rotation_matrix,
    convert_sequence,
    matrix_derivatives,
    matrix_from_rotvec,
    rotvec_from_matrix,
)

angle = st.floats(-3.0, 3.0)
SEQS = ["opk", "pok"]


def test_opk_matrix_written_out():
    # R = R_omega R_phi R_kappa, element by element (Kraus' table)
    w, p, k = 0.1, -0.2, 0.3
    cw, sw, cp, sp, ck, sk = np.cos(w), np.sin(w), np.cos(p), np.sin(p), np.cos(k), np.sin(k)
    expected = np.array(
        [
            [cp * ck, -cp * sk, sp],
            [cw * sk + sw * sp * ck, cw * ck - sw * sp * sk, -sw * cp],
            [sw * sk - cw * sp * ck, sw * ck + cw * sp * sk, cw * cp],
        ]
    )
    np.testing.assert_allclose(ov.matrix_from_opk(w, p, k), expected, atol=1e-15)


def test_pok_is_phi_first():
    w, p, k = 0.1, -0.2, 0.3
    Rw = ov.matrix_from_opk(w, 0, 0)
    Rp = ov.matrix_from_opk(0, p, 0)
    Rk = ov.matrix_from_opk(0, 0, k)
    np.testing.assert_allclose(ov.matrix_from_opk(w, p, k, "pok"), Rp @ Rw @ Rk, atol=1e-15)
    np.testing.assert_allclose(ov.matrix_from_opk(w, p, k, "opk"), Rw @ Rp @ Rk, atol=1e-15)


def test_small_rotation_signs():
    # a positive omega turns +Y towards +Z (right-handed about X)
    R = ov.matrix_from_opk(0.01, 0, 0)
    assert R[2, 1] > 0 and R[1, 2] < 0


@pytest.mark.parametrize("seq", SEQS)
@settings(max_examples=60, deadline=None)
@given(w=angle, p=st.floats(-1.5, 1.5), k=angle)
def test_round_trip(seq, w, p, k):
    angles = (w, p, k) if seq == "opk" else (p, w, k)  # secondary angle in (-pi/2, pi/2)
    R = ov.matrix_from_opk(*angles, sequence=seq)
    back = ov.opk_from_matrix(R, seq)
    np.testing.assert_allclose(ov.matrix_from_opk(*back, sequence=seq), R, atol=1e-12)
    np.testing.assert_allclose(back, angles, atol=1e-9)


@pytest.mark.parametrize("seq", SEQS)
@settings(max_examples=40, deadline=None)
@given(w=angle, p=angle, k=angle)
def test_derivatives_match_finite_differences(seq, w, p, k):
    a = np.array([w, p, k])
    d = matrix_derivatives(*a, sequence=seq)
    h = 1e-6
    for i in range(3):
        e = np.zeros(3)
        e[i] = h
        fd = (
            ov.matrix_from_opk(*(a + e), sequence=seq) - ov.matrix_from_opk(*(a - e), sequence=seq)
        ) / (2 * h)
        np.testing.assert_allclose(d[i], fd, atol=1e-8)


@pytest.mark.parametrize(
    "seq,angles",
    [
        ("opk", (0.4, np.pi / 2, 0.3)),
        ("opk", (0.4, -np.pi / 2, -0.2)),
        ("pok", (np.pi / 2, 0.4, 0.3)),
        ("pok", (-np.pi / 2, 0.1, 0.7)),
    ],
)
def test_gimbal_lock_gives_same_matrix(seq, angles):
    R = ov.matrix_from_opk(*angles, sequence=seq)
    back = ov.opk_from_matrix(R, seq)
    assert back[2] == 0.0  # kappa set to zero by convention
    np.testing.assert_allclose(ov.matrix_from_opk(*back, sequence=seq), R, atol=1e-12)


def test_vectorised_and_conversion():
    rng = np.random.default_rng(0)
    a = rng.uniform(-1, 1, (5, 3))
    R = ov.matrix_from_opk(a[:, 0], a[:, 1], a[:, 2])
    assert R.shape == (5, 3, 3)
    b = convert_sequence(a[:, 0], a[:, 1], a[:, 2], "opk", "pok")
    np.testing.assert_allclose(ov.matrix_from_opk(*b, sequence="pok"), R, atol=1e-12)


def test_rotvec_round_trip_near_pi():
    R = ov.matrix_from_opk(0.01, -0.02, np.pi - 1e-9)
    np.testing.assert_allclose(matrix_from_rotvec(rotvec_from_matrix(R)), R, atol=1e-9)


@pytest.mark.parametrize(
    "bad,msg",
    [
        (np.eye(2), "shape"),
        (np.diag([1, 1, -1.0]), "reflection"),
        (2 * np.eye(3), "orthonormal"),
        (np.full((3, 3), np.nan), "finite"),
    ],
)
def test_check_rotation_matrix_messages(bad, msg):
    with pytest.raises(ValueError, match=msg):
        check_rotation_matrix(bad)


def test_unknown_sequence():
    with pytest.raises(ValueError, match="expected a rotation sequence"):
        ov.matrix_from_opk(0, 0, 0, "kpo")
