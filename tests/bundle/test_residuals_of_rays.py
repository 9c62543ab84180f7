"""BundleProblem.residuals_of_rays (the precision's far points at their placed state):
the rays of moved points evaluated again, the others taken over — the same numbers as a
full evaluation at the new state, with and without a camera model."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import orientviz as ov
from orientviz.bundle import LensModel
from orientviz.bundle.problem import BundleProblem, BundleState, point_setup
from orientviz.simulate import simulate_calibration


def _pinhole():
    block = ov.simulate_block(2, 5, rng=3, extra=8, control="perimeter").block
    return block, BundleProblem(block, point_setup(block, "fixed"), additional="brown")


def _lens():
    block = simulate_calibration(np.random.default_rng(1), kind="forward", sigma_mm=3e-4).block
    lens = LensModel("forward", free=("c", "k1", "k2"))
    prob = BundleProblem(block, point_setup(block, "fixed"), additional=lens,
                         ap_group=np.arange(block.n_images))  # fmt: skip
    return block, prob


@pytest.mark.parametrize("make", [_pinhole, _lens])
def test_residuals_of_rays_equal_a_full_evaluation(make):
    block, prob = make()
    rng = np.random.default_rng(5)
    ap = 1e-3 * rng.standard_normal(prob.q)
    st = BundleState(
        block.images.X0.copy(), block.images.angles.copy(), block.points.xyz.copy(), ap
    )
    rw, Je, Jp = prob.residuals(st, jac=True)
    # two point unknowns moved along (a little and far)
    cols = np.array([1, 4])
    pts = prob.points.unknown[cols]
    xyz = st.xyz.copy()
    xyz[pts] += np.array([[0.3, -0.2, 0.1], [40.0, 25.0, 300.0]])
    moved = replace(st, xyz=xyz)
    rays = np.flatnonzero(np.isin(prob.obs.column, cols))
    got = prob.residuals_of_rays(moved, rays, rw, Je, Jp)
    design = prob.ap.Aw.copy() if prob.ap.lens is not None else None
    want = prob.residuals(moved, jac=True)
    for g, w in zip(got, want, strict=True):
        assert g.tobytes() == w.tobytes()
    assert not np.array_equal(got[0][rays], rw[rays])  # the moved rays did change
    if design is not None:  # the camera model's design is the one at the moved state
        assert design.tobytes() == prob.ap.Aw.tobytes()
