"""Structural changes by the live update (images added, moved, removed; cross strips;
control after them) equal a new assessment of the changed design."""

from __future__ import annotations

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

import orientviz as ov
from orientviz.design import (
    FlightDesign,
    LiveDesign,
    assess_block,
    cross_strip_images,
    design_auxiliary,
    design_block,
    remove_images,
)
from orientviz.errors import InputError, NotDeterminableError


@pytest.fixture(scope="module", autouse=True)
def _one_thread():
    with threadpool_limits(1, "blas"):
        yield


@pytest.fixture(scope="module")
def base():
    block, spec = design_block(FlightDesign(strips=3, images_per_strip=8, control="perimeter"))
    return block, spec, LiveDesign(block, spec)


def _same(q, b, spec):
    """q equals a new assessment of block b (the update's rounding: ~1e-8 relative on this
    perimeter design; a new assessment of the same block repeats itself to ~1e-12)."""
    ref = assess_block(b, spec)[1]
    np.testing.assert_allclose(q.point_sigma, ref.point_sigma, rtol=1e-7)
    np.testing.assert_allclose(q.station_sigma, ref.station_sigma, rtol=1e-7)
    np.testing.assert_allclose(q.redundancy, ref.redundancy, atol=1e-9)
    fin = np.isfinite(ref.mdb)
    assert np.array_equal(fin, np.isfinite(q.mdb))
    np.testing.assert_allclose(q.mdb[fin], ref.mdb[fin], rtol=1e-7)
    np.testing.assert_allclose(q.external[fin], ref.external[fin], rtol=1e-7)
    np.testing.assert_allclose(q.point_shift[fin], ref.point_shift[fin], rtol=1e-6)
    assert q.weak_spots == ref.weak_spots
    assert q.summary.keys() == ref.summary.keys()


def _updated(live):
    assert not any("formed and factored again" in t for t in live.history), live.history


def test_an_image_removed_and_added_by_the_update_equals_a_new_assessment(base):
    block, spec, live = base
    rm = live.remove_images([9])  # inside strip 1: some points lose their second ray
    assert rm.block.n_images == block.n_images - 1 and rm.block.n_points < block.n_points
    _updated(rm)
    _same(rm.quality(), rm.block, spec)
    I = rm.block.images
    add = rm.add_images(I.X0[4] + [250.0, -120.0, 0.0], I.angles[4], strip=int(I.strip[4]))
    _updated(add)
    _same(add.quality(), add.block, spec)
    # control after the structural steps, and its undo
    tie = np.flatnonzero(add.block.points.role == ov.TIE)
    q = add.add_control(int(tie[len(tie) // 2]), 0.02)
    _same(q, add.block, spec)
    q = add.remove_control(int(np.flatnonzero(add.block.points.role == ov.CONTROL)[0]))
    _same(q, add.block, spec)
    add.undo()
    q = add.undo()
    _same(q, add.block, spec)
    # the designs before stay as they were (the studio's undo keeps them)
    _same(live.quality(), live.block, spec)
    _same(rm.quality(), rm.block, spec)


def test_a_cross_strip_and_a_removed_strip_by_the_update_equal_new_assessments(base):
    block, spec, live = base
    X0, ang, strip, ids = cross_strip_images(block, spec, float(np.median(block.points.xyz[:, 0])))
    cs = live.add_images(X0, ang, strip=strip, ids=ids)
    _updated(cs)
    assert cs.block.images.ids[-len(ids) :] == ids
    _same(cs.quality(), cs.block, spec)
    rs = cs.remove_images(np.flatnonzero(cs.block.images.strip == 2))
    _updated(rs)
    _same(rs.quality(), rs.block, spec)
    # a step too large for the update: the same numbers by a new assessment
    cs.max_columns = 10
    big = cs.remove_images(np.flatnonzero(cs.block.images.strip == 2))
    assert "formed and factored again" in big.history[-1]
    np.testing.assert_allclose(big.quality().point_sigma, rs.quality().point_sigma, rtol=1e-7)


def test_a_removal_that_disconnects_the_block_is_not_determinable(base):
    block, spec, live = base
    with pytest.raises(NotDeterminableError, match="not determinable"):
        live.remove_images(np.flatnonzero(block.images.strip == 1))  # strips 0, 2 apart
    with pytest.raises(NotDeterminableError):
        assess_block(remove_images(block, np.flatnonzero(block.images.strip == 1)), spec)


@pytest.mark.parametrize(
    "aux",
    [
        dict(sigma_statoscope=0.3, sigma_apr=0.5),
        dict(sigma_gnss=0.1, gnss_offsets=True),
    ],
    ids=["statoscope+apr", "gnss-shift"],
)
def test_images_of_a_design_with_auxiliary_data_update_their_rows(aux):
    plan = FlightDesign(strips=3, images_per_strip=7, control="perimeter", **aux)
    block, spec = design_block(plan)
    live = LiveDesign(block, spec, auxiliary=design_auxiliary(block, plan))
    with pytest.raises(InputError, match="auxiliary"):
        live.remove_images([3])  # the rows follow the images: the new data are needed

    def of(b):
        return design_auxiliary(b, plan)

    def same(lv):
        ref = assess_block(lv.block, spec, auxiliary=of(lv.block))[1]
        np.testing.assert_allclose(lv.quality().point_sigma, ref.point_sigma, rtol=1e-7)
        np.testing.assert_allclose(lv.quality().station_sigma, ref.station_sigma, rtol=1e-7)
        np.testing.assert_allclose(lv.quality().redundancy, ref.redundancy, atol=1e-9)
        fin = np.isfinite(ref.external)
        np.testing.assert_allclose(lv.quality().external[fin], ref.external[fin], rtol=1e-7)

    rm = live.remove_images([9], auxiliary=of)  # inside strip 1: its readings go too
    _updated(rm)
    same(rm)
    I = rm.block.images
    add = rm.add_images(I.X0[4] + [200.0, 0.0, 0.0], I.angles[4], strip=int(I.strip[4]),
                        auxiliary=of)  # fmt: skip
    _updated(add)
    same(add)
    tie = np.flatnonzero(add.block.points.role == ov.TIE)
    add.add_control(int(tie[len(tie) // 3]), 0.05)  # control after, with the border
    same(add)
    # a cross strip is a new strip: new offsets, a new design
    X0, ang, strip, ids = cross_strip_images(block, spec, float(np.median(block.points.xyz[:, 0])))
    cs = live.add_images(X0, ang, strip=strip, ids=ids, auxiliary=of)
    assert "formed and factored again" in cs.history[-1]
    same(cs)


def test_the_block_solve_equals_the_factors_solve():
    from orientviz.design._base import DesignBase  # a unit test of the package's module

    block, _ = design_block(FlightDesign(strips=4, images_per_strip=12, control="perimeter"))
    base = DesignBase(block)
    assert base.fac.kind == "banded"  # the blocks are what is tested
    rhs = np.random.default_rng(3).normal(size=(6 * block.n_images, 9))
    np.testing.assert_allclose(base.solve(rhs), base.fac.solve(rhs), rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize(
    "aux",
    [dict(sigma_statoscope=0.3, sigma_apr=0.5), dict(sigma_gnss=0.1, gnss_offsets=True)],
    ids=["statoscope+apr", "gnss-shift"],
)
def test_the_banded_precision_of_a_design_with_auxiliary_data_equals_the_dense(aux):
    """Large designs take the banded selected inverse and the offsets' border S⁻¹E by the
    same band factor; small ones (all other tests here) the dense inverse."""
    from orientviz.bundle import BundleOptions, bundle_adjust

    plan = FlightDesign(strips=3, images_per_strip=7, control="perimeter", **aux)
    block, _ = design_block(plan)
    kw = dict(control="weighted", precision=True, max_iter=3,
              auxiliary=design_auxiliary(block, plan))  # fmt: skip
    dense = bundle_adjust(block, **kw)
    band = bundle_adjust(block, options=BundleOptions(dense_inverse_limit=0), **kw)
    for key in ("points", "exterior", "auxiliary"):
        a, b = band.cofactor_groups[key], dense.cofactor_groups[key]
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12 * np.abs(b).max())
    np.testing.assert_allclose(band.redundancy_numbers, dense.redundancy_numbers, atol=1e-10)
    np.testing.assert_allclose(band.ray_gains.exterior, dense.ray_gains.exterior, atol=1e-10)
