"""Systematic image error models: magnitudes, formulas, per-group use, simulator hook."""

import numpy as np
import pytest

import orientviz as ov
from orientviz.simulate import systematic as se

XY = np.array([[110.0, 0.0], [0.0, 110.0], [-80.0, 60.0], [0.0, 0.0]])
IMG = np.zeros(4, np.int64)


def test_affinity_magnitudes_are_exact_at_the_reference():
    d = se.affinity(6.0, 3.0)(XY, IMG)
    np.testing.assert_allclose(d[0], [0.006, 0.003], atol=1e-15)
    np.testing.assert_allclose(d[1], [0.0, 0.0], atol=1e-15)


def test_radial_profile_and_direction():
    m = se.radial(7.0, ref_mm=150.0, k2_fraction=-0.5)
    p = np.array([[150.0 * np.cos(0.3), 150.0 * np.sin(0.3)]])
    d = m(p, [0])[0]
    assert np.hypot(*d) == pytest.approx(0.007, rel=1e-12)
    assert p[0, 0] * d[1] - p[0, 1] * d[0] == pytest.approx(0.0, abs=1e-15)  # purely radial
    assert np.all(m(np.zeros((1, 2)), [0]) == 0.0)


def test_decentering_matches_brown_conrady():
    m = se.decentering(3.0, ref_mm=150.0, angle_deg=0.0)  # p2 = 0
    p1 = 0.003 / 150.0**2
    x, y = -80.0, 60.0
    d = m(np.array([[x, y]]), [0])[0]
    r2 = x * x + y * y
    np.testing.assert_allclose(d, [p1 * (r2 + 2 * x * x), 2 * p1 * x * y], rtol=1e-12)


@pytest.mark.parametrize("b", [92.0, 60.0])
def test_twist_and_bending_give_the_stated_parallax(b):
    rng = np.random.default_rng(0)
    x = rng.uniform(b - 110, 110, 50)
    y = rng.uniform(-110, 110, 50)
    left, right = np.column_stack([x, y]), np.column_stack([x - b, y])
    tw = se.model_twist(8.0, base_mm=b)
    px = tw(left, np.zeros(50, int))[:, 0] - tw(right, np.zeros(50, int))[:, 0]
    a = 0.008 / (b * b * 110.0)
    np.testing.assert_allclose(px, 2 * a * b * y * (x - b / 2), rtol=1e-10, atol=1e-15)
    # at the model corner the parallax error is the stated 8 µm
    corner = np.array([[b, 110.0]]), np.array([[0.0, 110.0]])
    assert tw(corner[0], [0])[0, 0] - tw(corner[1], [0])[0, 0] == pytest.approx(0.008)
    be = se.model_bending(8.0, base_mm=b)
    pb = be(left, np.zeros(50, int))[:, 0] - be(right, np.zeros(50, int))[:, 0]
    np.testing.assert_allclose(pb, 0.008 * (y / 110.0) ** 2, rtol=1e-10, atol=1e-15)


def test_sum_per_group_and_typical_magnitude():
    a, t = se.affinity(5.0, 0.0), se.trapezoid(4.0)
    s = a + t
    np.testing.assert_allclose(s(XY, IMG), a(XY, IMG) + t(XY, IMG))
    pg = se.PerGroup([a, None], group=[0, 1, 0])
    d = pg(np.array([[110.0, 0], [110.0, 0], [55.0, 0]]), [0, 1, 2])
    np.testing.assert_allclose(d[:, 0], [0.005, 0.0, 0.0025])
    with pytest.raises(ov.InputError, match="only 2 models"):
        se.PerGroup([a, None], group=[0, 2])
    # the error fields are linear in their amplitudes, so the scaling is exact
    assert se.magnitude_um(se.typical(10.0)) == pytest.approx(10.0, rel=1e-9)
    assert se.magnitude_um(se.typical(4.0)) == pytest.approx(4.0, rel=1e-9)


def test_film_deformation_differs_per_image_with_the_requested_rms():
    rng = np.random.default_rng(5)
    fd = se.film_deformation(rng, 400, rms_um=2.0)
    g = np.linspace(-110, 110, 12)
    gx, gy = np.meshgrid(g, g)
    xy = np.column_stack([gx.ravel(), gy.ravel()])
    d = np.stack([fd(xy, np.full(xy.shape[0], i)) for i in range(400)])
    # 400 images x 144 points: the sample rms is within a few % of 2 µm
    assert np.sqrt(np.mean(d**2)) * 1e3 == pytest.approx(2.0, rel=0.1)
    assert not np.allclose(d[0], d[1])
    with pytest.raises(ov.InputError, match="defined for 400 images"):
        fd(xy[:1], [400])


def test_bad_coordinates_are_rejected():
    with pytest.raises(ov.InputError, match=r"expected shape \(n, 2\)"):
        se.affinity()(np.zeros((3, 3)), [0, 0, 0])
    with pytest.raises(ov.InputError, match="axis"):
        se.trapezoid(axis="z")


def test_simulator_hook_adds_the_error_at_the_true_coordinates():
    from orientviz.simulate import simulate_block

    err = se.affinity(8.0, 2.0) + se.radial(6.0)
    sim = simulate_block(1, 3, rng=1, extra=None, sigma_image_mm=0.0, systematic=err)
    truth_xy = sim.truth.observations.xy
    expected = err(truth_xy, sim.truth.observations.image)
    np.testing.assert_allclose(sim.info["systematic"], expected, atol=1e-15)
    np.testing.assert_allclose(sim.block.observations.xy - truth_xy, expected, atol=1e-12)
