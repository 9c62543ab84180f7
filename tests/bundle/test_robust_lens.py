"""A robust loss with a camera model: trial points without derivatives change nothing.

A camera model's trial points are evaluated without derivatives (BundleSteps.defer) and
a robust loss then sets its weights from the known misclosures before the design is
formed once (bundle/loop/_steps.py). The run must be the one that forms the derivatives
at every trial point: the same iterations, the same numbers.
"""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.bundle import BundleOptions, LensModel, bundle_adjust
from orientviz.bundle.loop import _steps
from orientviz.simulate import simulate_calibration

CAMERA = {"c": 7.31, "x0": 0.03, "y0": -0.02, "k1": -0.1, "k2": 0.05, "p1": 1e-3}


@pytest.fixture(scope="module")
def outliers():
    """A forward camera's calibration images with 4 % of the rays moved by 20–40 µm, and
    k2 of the least-squares solutions with and without those rays."""
    rng = np.random.default_rng(28)
    sim = simulate_calibration(rng, kind="forward", camera=CAMERA, sigma_mm=3e-4)
    clean = sim.block.copy()
    xy = sim.block.observations.xy
    k = rng.choice(xy.shape[0], xy.shape[0] // 25, replace=False)
    ang = rng.uniform(0.0, 2.0 * np.pi, k.size)
    xy[k] += rng.uniform(0.02, 0.04, k.size)[:, None] * np.column_stack([np.cos(ang), np.sin(ang)])
    opts = BundleOptions(damping="trust", max_iter=40)
    k2 = [
        bundle_adjust(b, additional=LensModel("forward"), options=opts, precision=False).camera.get(
            "k2"
        )[0]
        for b in (clean, sim.block)
    ]
    return sim.block, k2


@pytest.mark.parametrize("loss", ["huber", "cauchy"])
def test_deferred_derivatives_give_the_same_run(outliers, loss, monkeypatch):
    block, (k2_clean, k2_lsq) = outliers
    opts = BundleOptions(loss=loss, loss_scale=2.0, damping="trust", max_iter=40)
    lens = LensModel("forward")
    deferred = bundle_adjust(block, additional=lens, options=opts, precision=False)
    assert deferred.converged
    real_init = _steps.BundleSteps.__init__

    def eager(self, *a, **k):  # derivatives at every trial point, as before the deferral
        real_init(self, *a, **k)
        self.defer = False

    monkeypatch.setattr(_steps.BundleSteps, "__init__", eager)
    formed = bundle_adjust(block, additional=lens, options=opts, precision=False)
    assert [h.cost for h in deferred.history] == [h.cost for h in formed.history]
    assert np.array_equal(deferred.x, formed.x)
    # the loss acted: k2 near the clean data's (least squares with the outliers: 0.18 off)
    assert abs(deferred.camera.get("k2")[0] - k2_clean) < 0.2 * abs(k2_lsq - k2_clean)
