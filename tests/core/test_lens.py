"""Lens models: the backward (DBAT/PhotoModeler) model, its Jacobian, conversion to OpenCV."""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.lens import (
    BackwardLens,
    backward_ideal,
    backward_ideal_jacobian,
    forward_from_backward,
    forward_pixels,
)

#: DBAT's calibrated Olympus C4040Z (camcal demo, our estimate; py in the y-up frame)
CAMCAL = BackwardLens(7.456995, 3.615462, -2.613293, (4.588607e-3, -4.513511e-5, -2.052533e-6),
                      (-6.128034e-5, -4.411716e-5), 3.895975e-4)  # fmt: skip


def test_jacobian_matches_central_differences():
    rng = np.random.default_rng(1)
    m = rng.uniform([0, -5.4], [7.25, 0], (40, 2))
    lens = BackwardLens(CAMCAL.c, CAMCAL.px, CAMCAL.py, CAMCAL.K, CAMCAL.P, CAMCAL.aspect, 2e-4)
    J = backward_ideal_jacobian(m, lens)
    v = lens.vector()
    for k, i in enumerate(range(1, 10)):
        h = 1e-6 * max(abs(v[i]), 1e-2)
        a, b = v.copy(), v.copy()
        a[i] += h
        b[i] -= h
        num = (
            backward_ideal(m, BackwardLens.from_vector(a))
            - backward_ideal(m, BackwardLens.from_vector(b))
        ) / (2 * h)
        assert np.allclose(J[:, :, k], num, rtol=1e-5, atol=1e-6 * np.abs(num).max()), (
            k
        )  # FD noise ~1e-8


def test_no_distortion_is_the_plain_centred_point():
    m = np.array([[1.0, -2.0], [3.0, -1.0]])
    lens = BackwardLens(7.0, 0.5, -0.25)
    assert np.allclose(backward_ideal(m, lens), m - [0.5, -0.25])


def test_affinity_acts_before_the_distortion():
    """DBAT's model 3: z = A · x first, then the radial term of z (not of x)."""
    m = np.array([[3.0, -1.0]])
    lens = BackwardLens(7.0, 0.0, 0.0, (1e-3, 0.0, 0.0), (0.0, 0.0), 0.01)
    z = np.array([3.0 * 1.01, -1.0])
    expect = z * (1 + 1e-3 * (z @ z))
    assert np.allclose(backward_ideal(m, lens), expect)


def test_conversion_to_opencv_without_distortion_is_exact():
    lens = BackwardLens(7.5, 3.6, -2.7)
    conv = forward_from_backward(lens, 0.0032, (2272, 1704))
    assert conv.max_px < 1e-6
    fx, fy, cx, cy = conv.forward[:4]
    assert fx == pytest.approx(7.5 / 0.0032) and fy == pytest.approx(fx)
    assert cx == pytest.approx(3.6 / 0.0032) and cy == pytest.approx(2.7 / 0.0032)


def test_conversion_of_the_calibrated_camera_reports_what_stays():
    conv = forward_from_backward(CAMCAL, 5.43764 / 1704, (2272, 1704))
    # the two families differ (the distortion of the measured vs of the ideal point):
    # OpenCV's best fit leaves 0.38 px at the corners, 0.03 px r.m.s. over the image
    assert conv.rms_px < 0.05 and conv.max_px < 0.5
    k1 = conv.forward[4]
    assert k1 < 0  # barrel distortion: backward K1 > 0 corrects outward, forward k1 < 0
    xn = np.array([[0.1, -0.2]])
    assert forward_pixels(xn, conv.forward).shape == (1, 2)
