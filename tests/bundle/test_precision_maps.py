"""The precision forms S at the solution with the Schur maps of the iterations (not
formed a second time), and the maps are released when the precision does not need them."""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.bundle import BundleOptions, LensModel
from orientviz.bundle.reduced import ReducedOptions, _tracks
from orientviz.simulate import simulate_calibration

#: S formed by pairs of rays (the Schur maps) and factored densely: the camera blocks
OPTIONS = BundleOptions(solver="dense", reduced=ReducedOptions(pair_ns=1e-3))


@pytest.fixture
def builds(monkeypatch):
    """The d of each build of the Schur maps (per d at most once while they are held)."""
    count = []
    real = _tracks.TrackGroups.maps

    def counted(self, keys, m, d=6):
        if d not in self._maps:
            count.append(d)
        return real(self, keys, m, d)

    monkeypatch.setattr(_tracks.TrackGroups, "maps", counted)
    return count


def test_the_precision_reuses_the_maps_of_the_iterations(builds):
    block = simulate_calibration(np.random.default_rng(1), kind="forward", sigma_mm=3e-4).block
    res = ov.bundle_adjust(
        block, additional=LensModel("forward", free=("c", "k1", "k2")),
        ap_group=np.arange(block.n_images), options=OPTIONS,
    )  # fmt: skip
    assert res.converged and res.redundancy_numbers is not None
    assert builds and sorted(builds) == sorted(set(builds))  # (a held first step: d = 6)


def test_without_precision_the_maps_are_released(monkeypatch):
    kept = []
    real = _tracks.TrackGroups.maps

    def spy(self, *a, **k):
        kept.append(self)
        return real(self, *a, **k)

    monkeypatch.setattr(_tracks.TrackGroups, "maps", spy)
    block = simulate_calibration(np.random.default_rng(1), kind="forward", sigma_mm=3e-4).block
    res = ov.bundle_adjust(
        block, additional=LensModel("forward", free=("c", "k1", "k2")),
        ap_group=np.arange(block.n_images), options=OPTIONS, precision=False,
    )  # fmt: skip
    assert res.converged and kept
    assert kept[-1]._maps == {} and kept[-1].work == {}
