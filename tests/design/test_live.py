"""Live design: the low-rank update equals a new assessment of the changed design."""

from __future__ import annotations

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

import orientviz as ov
from orientviz.design import FlightDesign, LiveDesign, assess_block, design_block
from orientviz.errors import InputError


@pytest.fixture(scope="module", autouse=True)
def _one_thread():
    with threadpool_limits(1, "blas"):
        yield


@pytest.fixture(scope="module")
def base():
    return design_block(FlightDesign(strips=3, images_per_strip=7, control="corners"))


def _same(q, ref):
    # the corner-controlled base design is weak (cond(N) ≈ 1e12, σ_Z of metres in the
    # middle): the columns of Q0 carry relative errors of ~1e-6 there (a dense inverse of
    # N agrees with a new assessment to 2e-12 and with the update to 2e-6)
    np.testing.assert_allclose(q.point_sigma, ref.point_sigma, rtol=1e-5)
    np.testing.assert_allclose(q.station_sigma, ref.station_sigma, rtol=1e-5)
    np.testing.assert_allclose(q.redundancy, ref.redundancy, atol=1e-7)
    fin = np.isfinite(ref.mdb)
    assert np.array_equal(fin, np.isfinite(q.mdb))
    np.testing.assert_allclose(q.mdb[fin], ref.mdb[fin], rtol=1e-6)
    np.testing.assert_allclose(q.external[fin], ref.external[fin], rtol=1e-5)
    np.testing.assert_allclose(q.point_shift[fin], ref.point_shift[fin], rtol=1e-5)
    assert q.weak_spots == ref.weak_spots


def test_changes_by_update_equal_a_new_assessment(base):
    block, spec = base
    live = LiveDesign(block, spec)
    tie = np.flatnonzero(block.points.role == ov.TIE)
    ctrl = np.flatnonzero(block.points.role == ov.CONTROL)
    steps = [
        lambda: live.add_control(int(tie[len(tie) // 2]), 0.02),
        lambda: live.set_control(int(tie[3]), (np.nan, np.nan, 0.01)),  # height only
        lambda: live.remove_control(int(ctrl[0])),  # control of the base design goes
        lambda: live.set_control(int(tie[len(tie) // 2]), (0.05, 0.05, 0.05)),  # σ changed
    ]
    for step in steps:
        q = step()
        _, ref = assess_block(live.block, spec)
        _same(q, ref)
    # undo returns to the earlier designs
    q = live.undo()
    _, ref = assess_block(live.block, spec)
    _same(q, ref)
    assert len(live.changes) == 3 and live.history[-1].startswith("undo")
    # adding control shrinks σ where it is placed
    j = int(tie[len(tie) // 2])
    assert q.point_sigma[j, 2] < live.base_quality.point_sigma[j, 2]


def test_undo_to_the_start_gives_the_base_and_rebuild_keeps_the_numbers(base):
    block, spec = base
    live = LiveDesign(block, spec)
    tie = np.flatnonzero(block.points.role == ov.TIE)
    live.add_control(int(tie[5]))
    q = live.undo()
    assert q is live.base_quality
    with pytest.raises(InputError, match="nothing to undo"):
        live.undo()
    q1 = live.add_control(int(tie[7]))
    q2 = live.rebuild()
    _same(q1, q2)
