"""Polynomial strip and block adjustment (orientviz.polynomial)."""

import numpy as np
import pytest

import orientviz as ov
from orientviz.block import TIE, Observations
from orientviz.orientation.absolute import similarity_closed_form
from orientviz.polynomial import form_strips, polynomial_adjust
from orientviz.stereo_models import form_models


def noise_free(strips=2, images=6, **kw):
    kw.setdefault("extra", None)
    return ov.simulate_block(
        strips, images, rng=np.random.default_rng(21), sigma_image_mm=0.0, **kw
    )


def test_model_elements_agree_with_the_relative_orientation_module():
    s = noise_free(1, 3)
    ms = form_models(s.block)
    o = s.block.observations
    left, right = ms.models[0]
    common = np.intersect1d(o.point[o.image == left], o.point[o.image == right])
    xl = np.array([o.xy[(o.image == left) & (o.point == p)][0] for p in common])
    xr = np.array([o.xy[(o.image == right) & (o.point == p)][0] for p in common])
    b = ms.centres[0, 1, 0]
    res = ov.relative_orientation(xl, xr, s.block.cameras.c[0], kind="dependent", b=b)
    # same dependent-pair convention: O2 = (b, by, bz), R2 = R(ω, φ, κ); error-free images
    np.testing.assert_allclose(res.x[:5], ms.elements[0], atol=1e-8)


def test_noise_free_strips_are_similar_to_the_truth():
    s = noise_free(2, 6)
    for st in form_strips(s.block):
        tr = similarity_closed_form(st.xyz, s.truth.points.xyz[st.point])
        np.testing.assert_allclose(tr.apply(st.xyz), s.truth.points.xyz[st.point], atol=1e-6)
        np.testing.assert_allclose(tr.apply(st.centres), s.truth.images.X0[st.images], atol=1e-6)


@pytest.mark.parametrize("degree", [1, 2, 3])
def test_noise_free_block_gives_the_truth(degree):
    s = noise_free(2, 7, control="chains", chain_spacing=2)
    res = polynomial_adjust(s.block, degree_xy=degree, degree_z=degree, iterations=5)
    # the passes converge linearly (about 30 × per pass on this block)
    np.testing.assert_allclose(res.points, s.truth.points.xyz, atol=1e-5)


def test_block_polynomials_are_weaker_than_independent_models():
    # Ackermann §21: for blocks the polynomial methods are clearly less accurate than the
    # rigorous ones; perimeter control only, 3 strips. Mean over 2 blocks.
    e_poly, e_mod = [], []
    for seed in range(2):
        s = ov.simulate_block(3, 13, rng=np.random.default_rng(seed), extra=None, control_spacing=4)
        free = s.block.points.role == TIE
        p = polynomial_adjust(s.block, degree_xy=3, degree_z=3)
        m = ov.independent_models(s.block)
        e_poly.append(np.nanmean((p.points - s.truth.points.xyz)[free] ** 2, axis=0))
        e_mod.append(np.nanmean((m.points - s.truth.points.xyz)[free] ** 2, axis=0))
    rp, rm = np.sqrt(np.mean(e_poly, axis=0)), np.sqrt(np.mean(e_mod, axis=0))
    assert rp[2] > 2 * rm[2]  # heights: several times worse (5.3 m vs 1.1 m on 4 × 13 blocks)
    assert np.all(rp[:2] > rm[:2])  # planimetry: 0.09-0.10 m vs 0.08 m on 4 × 13 blocks


def test_bad_degree():
    s = noise_free(1, 4)
    with pytest.raises(ov.InputError):
        polynomial_adjust(s.block, degree_xy=7)


def test_broken_strip_is_named():
    s = ov.simulate_block(1, 5, rng=np.random.default_rng(3), extra="grid", sigma_image_mm=0.0)
    b = s.block.copy()
    o = b.observations
    # image 2 loses every point that image 0 sees: models (0,1) and (1,2) share nothing
    seen0 = np.unique(o.point[o.image == 0])
    keep = ~((o.image == 2) & np.isin(o.point, seen0))
    b.observations = Observations(o.image[keep], o.point[keep], o.xy[keep], o.sigma[keep])
    with pytest.raises(ov.NotDeterminableError) as exc:
        form_strips(b)
    assert "s00_000+s00_001" in str(exc.value) and "s00_001+s00_002" in str(exc.value)


def _z_error(sim, res):
    tie = sim.block.points.role == TIE
    return np.sqrt(np.nanmean((res.points - sim.truth.points.xyz)[tie, 2] ** 2))


def test_barely_determined_height_polynomials_are_named_with_their_sigma():
    # 3 strips with perimeter control every 4 bases: third-degree height polynomials of the
    # middle strip hang on two end controls and the ties (lesson 08's block app)
    sim = ov.simulate_block(3, 8, rng=np.random.default_rng(5), extra=None,
                            control="perimeter", control_spacing=4)  # fmt: skip
    weak = polynomial_adjust(sim.block, degree_xy=3, degree_z=3)
    s_xy, s_z = weak.sigma_strip
    med, worst = weak.sigma_correction["height"]
    assert worst > 100 * s_z and len(weak.weak) == 1 and "height" in weak.weak[0]
    assert "degree_z" in weak.weak[0] and weak.weak[0] in weak.reason
    # the predicted σ is of the size of the errors the simulation really has
    err = _z_error(sim, weak)
    assert err > 10.0 and med / 5 < err < 5 * worst
    # planimetry stays determined: not named, σ of its corrections near a strip coordinate's
    assert weak.sigma_correction["planimetry"][1] < 5 * s_xy
    # a lower degree on the same block is no longer named, and its error is small
    ok = polynomial_adjust(sim.block, degree_xy=1, degree_z=1)
    assert ok.weak == [] and ok.reason == "linear adjustments (one step each)"
    assert _z_error(sim, ok) < 1.0 and ok.sigma_correction["height"][1] < 100 * s_z


def test_sigma_of_the_corrections_scales_with_the_strip_sigma():
    sim = ov.simulate_block(1, 8, rng=np.random.default_rng(3), extra=None)
    a = polynomial_adjust(sim.block, sigma_strip=(0.05, 0.10), iterations=1)
    b = polynomial_adjust(sim.block, sigma_strip=(0.15, 0.30), iterations=1)
    for part in ("planimetry", "height"):
        np.testing.assert_allclose(b.sigma_correction[part], 3 * np.array(a.sigma_correction[part]),
                                   rtol=1e-9)  # fmt: skip
        assert 0 < a.sigma_correction[part][0] <= a.sigma_correction[part][1]
