"""The first λ of the "trust" damping: least squares and robust runs start differently.

``bundle/loop/_adjust.py``: a least-squares run starts at ``TRUST_LAMBDA0``, a run with a
robust loss (whose first steps are least-squares steps pulled by the gross errors) at
``TRUST_LAMBDA0_ROBUST``; the "fallback" damping starts undamped whatever the loss.
"""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.bundle import BundleOptions, bundle_adjust
from orientviz.bundle.loop import _adjust, _steps
from orientviz.simulate import simulate_calibration


@pytest.fixture(scope="module")
def block():
    """A forward camera's calibration images, 4 % of the rays moved by 20–40 µm."""
    rng = np.random.default_rng(15)
    sim = simulate_calibration(rng, kind="forward", sigma_mm=3e-4)
    xy = sim.block.observations.xy
    k = rng.choice(xy.shape[0], xy.shape[0] // 25, replace=False)
    ang = rng.uniform(0.0, 2.0 * np.pi, k.size)
    xy[k] += rng.uniform(0.02, 0.04, k.size)[:, None] * np.column_stack([np.cos(ang), np.sin(ang)])
    return sim.block


def _first_lambda(block, monkeypatch, **options):
    seen = []
    real = _steps.BundleSteps.solve

    def solve(self, st, ev, lam, it):
        seen.append((it, lam))
        return real(self, st, ev, lam, it)

    monkeypatch.setattr(_steps.BundleSteps, "solve", solve)
    res = bundle_adjust(block, options=BundleOptions(max_iter=8, **options), precision=False)
    assert res.history[-1].cost < res.history[0].cost  # the run went on from its start
    return seen[0]


@pytest.mark.parametrize(
    ("options", "want"),
    [
        ({"damping": "trust"}, _adjust.TRUST_LAMBDA0),
        ({"damping": "trust", "loss": "huber"}, _adjust.TRUST_LAMBDA0_ROBUST),
        ({"damping": "trust", "loss": "cauchy"}, _adjust.TRUST_LAMBDA0_ROBUST),
        ({"damping": "fallback"}, 0.0),
        ({"damping": "fallback", "loss": "huber"}, 0.0),
    ],
)
def test_first_lambda_by_damping_and_loss(block, monkeypatch, options, want):
    assert _first_lambda(block, monkeypatch, **options) == (1, want)
    assert _adjust.TRUST_LAMBDA0 < _adjust.TRUST_LAMBDA0_ROBUST
