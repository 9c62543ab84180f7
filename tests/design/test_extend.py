"""Structural edits of a design (cross strips, removed images), a design from any block,
and the design for independent models — each against an adjustment of the simulated
block of the same layout."""

from __future__ import annotations

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from orientviz.bundle import bundle_adjust
from orientviz.camera import project
from orientviz.design import (
    FlightDesign,
    assess_block,
    assess_models,
    cross_strip,
    design_block,
    design_from_block,
    remove_images,
)
from orientviz.errors import InputError
from orientviz.stereo_models import independent_models

PLAN = FlightDesign(strips=2, images_per_strip=5, control="perimeter", control_spacing=2)


@pytest.fixture(scope="module", autouse=True)
def _one_thread():
    with threadpool_limits(1, "blas"):
        yield


@pytest.fixture(scope="module")
def base():
    block, spec = design_block(PLAN)
    return block, spec, assess_block(block, spec)[1]


@pytest.fixture(scope="module")
def crossed(base):
    block, spec, _ = base
    b = cross_strip(block, spec, float(block.images.X0[:, 0].max()))
    return b, assess_block(b, spec)


def _noisy_start(block, rng, start=(2.0, 0.002, 2.0)):
    """The design block as a simulated survey of it: image coordinates with errors of
    their σ, control with errors of its σ, start values off by ``start`` (m, rad, m)."""
    b = block.copy()
    o, P, im = b.observations, b.points, b.images
    o.xy = o.xy + rng.normal(0.0, 1.0, o.xy.shape) * o.sigma
    g = np.isfinite(P.xyz_known)
    P.xyz_known[g] += rng.normal(0.0, 1.0, int(g.sum())) * P.sigma[g]
    tie = ~g.any(axis=1)
    P.xyz[g] = P.xyz_known[g]
    P.xyz[tie] += rng.normal(0.0, start[2], (int(tie.sum()), 3))
    im.X0 += rng.normal(0.0, start[0], im.X0.shape)
    im.angles += rng.normal(0.0, start[1], im.angles.shape)
    return b


def test_the_cross_strip_flies_across_the_block_and_sees_its_points(base, crossed):
    block, spec, _ = base
    b, _ = crossed
    new = np.flatnonzero(b.images.strip == block.images.strip.max() + 1)
    assert new.size >= 3 and b.n_points == block.n_points
    X0 = b.images.X0[new]
    np.testing.assert_allclose(X0[:, 0], block.images.X0[:, 0].max())
    np.testing.assert_allclose(np.diff(X0[:, 1]), spec["base_m"])  # the block's base along Y
    o = b.observations
    mine = np.isin(o.image, new)
    assert np.unique(o.point[mine]).size >= 6
    R = b.rotations()
    xy = project(b.points.xyz[o.point], b.images.X0[o.image], R[o.image], b.cameras.c[0])
    np.testing.assert_allclose(o.xy, xy, atol=1e-9)  # error-free: the geometry itself
    assert np.abs(o.xy[mine]).max() <= 0.5 * 230.0 - 5.0 + 1e-9  # inside the format


def test_a_cross_strip_only_makes_sigma_smaller(base, crossed):
    _, _, q0 = base
    _, (_, q1) = crossed
    assert np.all(q1.point_sigma <= q0.point_sigma * (1 + 1e-9))
    assert q1.summary["sigma_z_rms"] < q0.summary["sigma_z_rms"]
    assert np.max(1 - q1.point_sigma[:, 2] / q0.point_sigma[:, 2]) > 0.05


def test_the_cross_strip_design_equals_the_adjusted_simulated_block(crossed):
    b, (res0, q) = crossed
    sim = _noisy_start(b, np.random.default_rng(11))
    res = bundle_adjust(sim, control="weighted", precision=True)
    assert res.converged
    sig = np.sqrt(np.einsum("nii->ni", res.cofactor_groups["points"]))
    np.testing.assert_allclose(sig, q.point_sigma, rtol=2e-3)
    sst = np.sqrt(np.einsum("nii->ni", res.cofactor_groups["exterior"]))
    np.testing.assert_allclose(sst, q.station_sigma, rtol=2e-3)
    n = b.n_observations
    r = np.asarray(res.redundancy_numbers[: 2 * n]).reshape(n, 2)
    np.testing.assert_allclose(r, q.redundancy, atol=2e-3)


def test_removing_an_image_never_improves_and_drops_lonely_points(base):
    block, spec, q0 = base
    b = remove_images(block, [0])
    assert b.n_images == block.n_images - 1
    assert b.rays_per_point().min() >= 2
    kept = [block.points.ids.index(i) for i in b.points.ids]
    assert len(kept) < block.n_points  # the corner points seen by image 0 alone went too
    q = assess_block(b, spec)[1]
    assert np.all(q.point_sigma >= q0.point_sigma[kept] * (1 - 1e-9))
    with pytest.raises(InputError, match="at least 2 images"):
        remove_images(block, np.arange(block.n_images - 1))


def test_a_design_from_a_block_reproduces_the_plan_and_weights_fixed_control(base):
    block, spec, q0 = base
    fixed = block.copy()
    fixed.points.sigma[np.isfinite(fixed.points.xyz_known)] = 0.0  # a file's fixed control
    fixed.observations.xy += 0.01  # measured coordinates: replaced by the projections
    b, sp = design_from_block(fixed, sigma_control=0.02)
    assert sp["base_m"] == pytest.approx(spec["base_m"], rel=1e-9)
    assert sp["flying_height_m"] == pytest.approx(spec["flying_height_m"], rel=1e-9)
    q = assess_block(b, sp)[1]
    np.testing.assert_allclose(q.point_sigma, q0.point_sigma, rtol=1e-6)
    with pytest.raises(InputError):
        design_from_block(block, sigma_control=0.0)


def test_the_models_design_equals_the_adjusted_simulated_block(base):
    block, spec, qb = base
    qm = assess_models(block, spec)
    tie = ~qm.control
    assert np.isfinite(qm.point_sigma[tie]).all() and np.isnan(qm.redundancy).all()
    # another method, another σ — but of the same size as the bundle's
    ratio = qm.summary["sigma_z_rms"] / qb.summary["sigma_z_rms"]
    assert 0.5 < ratio < 2.0 and abs(ratio - 1.0) > 1e-3
    sim = _noisy_start(block, np.random.default_rng(5), start=(0.5, 0.0005, 0.5))
    res = independent_models(sim, control="weighted", precision=True)
    assert res.converged
    Q = np.asarray(res.cofactor_groups["points"])
    k = np.asarray(res.point_index)
    sig = np.sqrt(np.einsum("nii->ni", Q[: k.size]))
    np.testing.assert_allclose(sig, qm.point_sigma[k], rtol=5e-3)


AUX_PLAN = FlightDesign(strips=2, images_per_strip=6, control="corners", sigma_statoscope=0.3,
                        sigma_apr=0.5)  # fmt: skip


@pytest.fixture(scope="module")
def aux_design():
    from orientviz.design import assess_design

    return assess_design(AUX_PLAN, law=False)


def test_statoscope_and_apr_never_make_the_heights_worse(aux_design):
    from orientviz.design import assess_design

    plain = assess_design(AUX_PLAN.with_(sigma_statoscope=None, sigma_apr=None), law=False)
    z0, z1 = plain.quality.point_sigma[:, 2], aux_design.quality.point_sigma[:, 2]
    assert np.all(z1 <= z0 * (1 + 1e-9))
    # offsets per strip: the readings stiffen each strip along its length (≥ 5 % here) but
    # cannot hold its roll, so the row between the strips stays weak (~1.4 m)
    assert np.max(1 - z1 / z0) > 0.05


def test_the_auxiliary_design_equals_the_adjusted_simulated_block(aux_design):
    from types import SimpleNamespace

    from orientviz.design import design_auxiliary
    from orientviz.simulate import simulate_auxiliary

    b = aux_design.block
    assert [a.kind for a in design_auxiliary(b, AUX_PLAN)] == ["statoscope", "apr"]
    rng = np.random.default_rng(21)
    sim = _noisy_start(b, rng)
    holder = SimpleNamespace(truth=b)  # readings with noise and a 20 m offset per strip
    aux = [
        simulate_auxiliary(holder, "statoscope", rng=rng, sigma=0.3, offset_sigma=20.0),
        simulate_auxiliary(holder, "apr", rng=rng, sigma=0.5, offset_sigma=20.0),
    ]
    res = bundle_adjust(sim, control="weighted", precision=True, auxiliary=aux)
    assert res.converged
    sig = np.sqrt(np.einsum("nii->ni", res.cofactor_groups["points"]))
    np.testing.assert_allclose(sig, aux_design.quality.point_sigma, rtol=2e-3)


def test_a_live_design_with_auxiliary_data_is_updated_exactly(aux_design):
    from orientviz.design import LiveDesign, design_auxiliary, set_control, suggest_control

    b, spec = aux_design.block, aux_design.spec
    aux = design_auxiliary(b, AUX_PLAN)
    live = LiveDesign(b, spec, auxiliary=aux)
    j = int(np.flatnonzero(b.points.role == 0)[3])
    q = live.add_control(j, 0.05)  # by the update formula with the offsets' border
    assert not any("formed and factored again" in t for t in live.history)
    ref = assess_block(set_control(b, j, (0.05, 0.05, 0.05)), spec, auxiliary=aux)[1]
    np.testing.assert_allclose(q.point_sigma, ref.point_sigma, rtol=1e-9)
    np.testing.assert_allclose(q.station_sigma, ref.station_sigma, rtol=1e-9)
    np.testing.assert_allclose(q.redundancy, ref.redundancy, atol=1e-10)
    fin = np.isfinite(ref.external)
    np.testing.assert_allclose(q.external[fin], ref.external[fin], rtol=1e-8)
    np.testing.assert_allclose(q.point_shift[fin], ref.point_shift[fin], rtol=1e-8)
    assert q.weak_spots == ref.weak_spots
    live.undo()
    np.testing.assert_allclose(live.quality().point_sigma, aux_design.quality.point_sigma)
    s = suggest_control(live, criterion="sigma_z", sigma=0.05)  # brute force with the border
    best = assess_block(set_control(b, s.point, (0.05,) * 3), spec, auxiliary=aux)[1]
    tie = ~best.control
    assert s.after == pytest.approx(best.point_sigma[tie, 2].max(), rel=1e-9)
    assert s.after == pytest.approx(s.values.min()) and len(live.changes) == 0


def test_gnss_with_a_shift_per_strip_equals_the_adjusted_block_and_is_weaker():
    from types import SimpleNamespace

    from orientviz.design import assess_design
    from orientviz.simulate import simulate_auxiliary

    plan = FlightDesign(strips=2, images_per_strip=6, control="corners", sigma_gnss=0.1)
    absolute = assess_design(plan, law=False)
    shifted = assess_design(plan.with_(gnss_offsets=True), law=False)
    assert np.isnan(shifted.block.images.X0_obs).all()  # as joint auxiliary data instead
    za, zs = absolute.quality.point_sigma[:, 2], shifted.quality.point_sigma[:, 2]
    assert np.all(zs >= za * (1 - 1e-9)) and zs.max() > 1.05 * za.max()
    b = shifted.block
    rng = np.random.default_rng(8)
    sim = _noisy_start(b, rng)
    gnss = simulate_auxiliary(
        SimpleNamespace(truth=b), "gnss", rng=rng, sigma=0.1, offset_sigma=2.0
    )
    res = bundle_adjust(sim, control="weighted", precision=True, auxiliary=[gnss])
    assert res.converged
    sig = np.sqrt(np.einsum("nii->ni", res.cofactor_groups["points"]))
    np.testing.assert_allclose(sig, shifted.quality.point_sigma, rtol=2e-3)
