"""Image and model deformation fields: closed-form twist/bending, absorption, animation."""

import numpy as np
import pytest

import orientviz as ov
from orientviz.bundle import Ebner12
from orientviz.simulate import animate, frames, image_field, model_field, model_fields, split_field
from orientviz.simulate import systematic as se


def _fit_height(f):
    x, y = f.xyz[:, 0] - f.xyz[:, 0].mean(), f.xyz[:, 1]
    M = np.column_stack([np.ones_like(x), x, y, x * y, y * y, x * x])
    return np.linalg.lstsq(M, f.d[:, 2], rcond=None)[0]


def test_twist_survives_orientation_with_the_closed_form_size():
    f = model_field(se.model_twist(8.0, base_mm=92.0), scale=10_000.0, n=5)
    a, b, s = 0.008 / (92.0**2 * 110.0), 92.0, 10_000.0
    # Δh = (H/B) · Δp_x(ground) = (H/B) · 2ab · X · Y · 1000/s  (X, Y in m)
    pred = f.height_m / f.base_m * 2 * a * b * 1000.0 / s
    coef = _fit_height(f)
    # linearised parallax formula vs rigorous orientation: agree to < 0.1 %
    assert coef[3] == pytest.approx(pred, rel=1e-3)
    assert np.abs(coef[[1, 2, 4, 5]]).max() < 1e-3 * abs(pred) * 1e3  # no tilt/bending left


def test_bending_across_the_flight_line():
    f = model_field(se.model_bending(8.0, base_mm=92.0), n=5)
    a, b = 0.008 / (92.0 * 110.0**2), 92.0
    pred = f.height_m / f.base_m * a * b * 1000.0 / 10_000.0
    assert _fit_height(f)[4] == pytest.approx(pred, rel=1e-3)


def test_error_free_images_give_no_deformation_and_trapezoid_is_absorbed():
    assert np.abs(model_field(None, n=4).d).max() < 1e-8
    # a projective (trapezoid) image error equals a tilt: relative orientation absorbs it
    assert np.abs(model_field(se.trapezoid(8.0), n=5).d).max() < 1e-4  # m, vs ~cm for affinity
    assert model_field(se.affinity(8.0, 0.0), n=5).rms()[0] > 0.01


def test_correcting_with_the_true_field_removes_the_deformation():
    err = se.typical(10.0)
    raw = model_field(err, n=5)
    cor = model_field(err, correction=err, n=5)
    # the correction is evaluated at the observed (not true) coordinates: second order
    assert np.abs(cor.d).max() < 1e-3 * np.abs(raw.d).max()
    assert "self-calibrated" in cor.name


def test_image_field_of_error_models_and_parameters():
    f = image_field(se.affinity(8.0, 0.0), half_mm=110.0, n=11)
    assert f.max_um == pytest.approx(8.0)
    assert f.xy.reshape(*f.shape, 2).shape == (11, 11, 2)
    p = np.zeros(12)
    p[0] = 5.0  # b1 = 5 µm
    g = image_field((Ebner12(b=92.0), p), half_mm=92.0, n=3)
    # b1: Δx = 5u, Δy = −5v µm: largest at the grid corner u = v = ±1
    assert g.max_um == pytest.approx(5.0 * np.sqrt(2.0))
    with pytest.raises(ov.InputError, match="expected a callable"):
        image_field(42)


def test_animation_interpolates_between_the_fields():
    a = model_field(se.affinity(8.0, 0.0), n=5)
    b = model_field(se.affinity(2.0, 0.0), n=5)
    np.testing.assert_allclose(animate(a, b, 0.0, 100.0), a.xyz + 100.0 * a.d)
    np.testing.assert_allclose(animate(a, b, 1.0, 100.0), b.xyz + 100.0 * b.d)
    fr = frames(a, b, n_frames=5, exaggeration=100.0)
    assert fr.shape == (5, 25, 3)
    np.testing.assert_allclose(fr[2], a.xyz + 50.0 * (a.d + b.d))
    with pytest.raises(ov.InputError, match="same grid"):
        animate(a, model_field(None, n=3), 0.5)
    with pytest.raises(ov.InputError, match=r"t in \[0, 1\]"):
        animate(a, b, 1.5)


def test_per_image_errors_give_per_model_fields():
    err = se.PerGroup([se.affinity(8.0, 0.0), se.model_twist(8.0)], group=[0, 0, 1, 1])
    f = model_fields(err, [[0, 1], [2, 3]], n=4)
    np.testing.assert_allclose(f[0].d, model_field(se.affinity(8.0, 0.0), n=4).d, atol=1e-9)
    np.testing.assert_allclose(f[1].d, model_field(se.model_twist(8.0), n=4).d, atol=1e-9)


def test_split_of_a_field_inside_the_span_recovers_its_parameters():
    p = np.array([3.0, -2.0, 0.0, 1.5, 0.0, 4.0, 0.0, -6.0, 0.0, 0.0, 2.5, 0.0])  # µm
    eb = Ebner12()
    inside = se.ImageError("ebner field", lambda xy: eb.correction(xy, p))
    s = split_field(inside, eb, n=9)
    np.testing.assert_allclose(s.params, p, atol=1e-9)
    np.testing.assert_allclose(s.orientation, 0.0, atol=1e-12)
    np.testing.assert_allclose(s.share, 1.0, atol=1e-12)
    assert s.rms_um[2] < 1e-9 * s.rms_um[0]
    # a pure scale + rotation of the image is the orientation's, not the set's
    eo = se.ImageError(
        "scale", lambda xy: 1e-4 * np.column_stack([xy[:, 0] - xy[:, 1], xy[:, 1] + xy[:, 0]])
    )
    s2 = split_field(eo, eb, n=9)
    np.testing.assert_allclose(s2.params, 0.0, atol=1e-9)
    np.testing.assert_allclose(s2.share, 1.0, atol=1e-12)


def test_split_of_the_film_trough_matches_a_polynomial_fit_per_coordinate():
    tr = se.unflatness(8.0)
    s = split_field(tr, Ebner12(), n=15)
    g = image_field(tr, n=15)
    # Ebner's 12 terms and the 6 orientation deformations span every Δx and Δy of degree
    # ≤ 2 in x and in y; the trough's Δx depends on x alone, so its best fit is the
    # quadratic polynomial in x through the grid values, and its Δy (y times a quadratic
    # in x) is inside the span
    x, dx = g.xy[:, 0], g.d[:, 0]
    r = dx - np.polyval(np.polyfit(x, dx, 2), x)
    assert s.share[0] == pytest.approx(1.0 - r @ r / (dx @ dx), rel=1e-9)
    assert s.share[1] == pytest.approx(1.0, abs=1e-12)
    assert 0.0 < s.share[0] < 0.5  # the cubic term: mostly outside the set
    # the two parts add up to the field everywhere, also off the grid
    xy = np.array([[13.0, -71.0], [-105.0, 98.0], [0.5, 3.0]])
    img = np.zeros(3, np.int64)
    np.testing.assert_allclose(s.described(xy, img) + s.remainder(xy, img), tr(xy, img), atol=1e-15)
    # a perfect self-calibration leaves the model the remainder's deformation (the
    # correction is evaluated at the observed coordinates: second order)
    left = model_field(tr, correction=s.described, n=5)
    np.testing.assert_allclose(
        left.d, model_field(s.remainder, n=5).d, atol=1e-3 * np.abs(left.d).max()
    )
    with pytest.raises(ov.InputError, match="n ≥ 3"):
        split_field(tr, Ebner12(), n=2)
