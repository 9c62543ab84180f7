"""The live independent-models design equals a new models assessment after every change.

``assess_models`` runs ``independent_models`` (iterated to corrections below 1e-4 σ_xy,
precision from the last linearisation); ``LiveModels`` linearises once at the design's
geometry and updates per control change. On error-free model coordinates the two
linearisation points differ by the iteration's last correction, a relative change of the
Jacobians far below 1e-8 (measured: 1e-11), so σ are compared to rtol 1e-8.
"""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.block import CONTROL, TIE
from orientviz.design import (
    FlightDesign,
    LiveModels,
    _models_live,
    assess_models,
    design_auxiliary,
    design_block,
)
from orientviz.errors import DatumDefectError, NotDeterminableError

RTOL = 1e-8


@pytest.fixture(scope="module")
def design():
    return design_block(FlightDesign(strips=4, images_per_strip=9, control_spacing=4))


def set_control(block, j: int, sigma) -> None:
    """Point ``j`` control with σ (m, NaN = not given; all NaN: tie), in place (as the
    studio's design changes its block)."""
    s = np.asarray(sigma, float)
    P = block.points
    P.sigma[j] = s
    P.xyz_known[j] = np.where(np.isfinite(s), P.xyz[j], np.nan)
    P.role[j] = CONTROL if np.isfinite(s).any() else TIE


def _same(q, block, spec, auxiliary=None):
    ref = assess_models(block, spec, auxiliary=auxiliary)
    np.testing.assert_allclose(q.point_sigma, ref.point_sigma, rtol=RTOL)
    np.testing.assert_allclose(q.station_sigma, ref.station_sigma, rtol=RTOL)
    np.testing.assert_allclose(q.point_cov, ref.point_cov, rtol=RTOL, atol=1e-14)
    assert q.weak_spots == ref.weak_spots
    assert q.summary == pytest.approx(ref.summary, rel=RTOL, nan_ok=True)


def test_the_base_equals_the_models_assessment(design):
    block, spec = design
    b = block.copy()
    _same(LiveModels(b, spec).quality(), b, spec)


def test_control_changes_and_their_undo_are_updates_equal_to_new_assessments(design):
    block, spec = design
    b = block.copy()
    live = LiveModels(b, spec)
    before = live.quality().point_sigma.copy()
    tie = np.flatnonzero(b.points.role == 0)
    inner = tie[
        np.argsort(np.linalg.norm(b.points.xyz[tie, :2] - b.points.xyz[:, :2].mean(0), axis=1))
    ]
    set_control(b, int(inner[0]), (0.02, 0.02, 0.02))
    q = live.sync()
    assert len(live._steps) == 1  # an update, no new factorisation
    assert q.point_sigma[inner[0], 2] < 0.5 * before[inner[0], 2]
    _same(q, b, spec)
    set_control(b, int(inner[1]), (np.nan, np.nan, 0.05))  # height only
    set_control(b, int(inner[2]), (0.03, 0.03, 0.03))  # two points in one sync
    _same(live.sync(), b, spec)
    set_control(b, int(inner[0]), (np.nan, np.nan, np.nan))  # back to a tie point
    set_control(b, int(inner[1]), (np.nan, np.nan, np.nan))
    set_control(b, int(inner[2]), (np.nan, np.nan, np.nan))
    q = live.sync()
    np.testing.assert_allclose(q.point_sigma, before, rtol=RTOL)


def test_after_max_steps_the_design_is_factored_again(design, monkeypatch):
    block, spec = design
    b = block.copy()
    live = LiveModels(b, spec)
    monkeypatch.setattr(_models_live, "MAX_STEPS", 2)
    tie = np.flatnonzero(b.points.role == 0)
    for j in tie[:3]:
        set_control(b, int(j), (0.02, 0.02, 0.02))
        q = live.sync()
    assert len(live._steps) < 2
    _same(q, b, spec)


def test_taking_the_datum_away_raises_and_keeps_the_design(design):
    block, spec = design
    b = block.copy()
    live = LiveModels(b, spec)
    q0 = live.quality()
    ctrl = np.flatnonzero(b.points.role == 1)
    for j in ctrl:
        set_control(b, int(j), (np.nan, np.nan, np.nan))
    with pytest.raises((DatumDefectError, NotDeterminableError)):
        live.sync()
    assert live.quality() is q0 and not live._steps
    for j in ctrl:  # the control back: nothing to change
        set_control(b, int(j), tuple(block.points.sigma[j]))
    assert live.sync() is q0


@pytest.mark.parametrize(
    "aux",
    [dict(sigma_statoscope=0.3, sigma_apr=0.5), dict(sigma_gnss=0.1, gnss_offsets=True)],
    ids=["statoscope+apr", "gnss-shift"],
)
def test_with_auxiliary_data_the_offsets_border_follows_every_change(aux):
    """The joint models adjustment (offsets per strip) by the border of the factor."""
    plan = FlightDesign(strips=3, images_per_strip=8, control="perimeter", **aux)
    b, spec = design_block(plan)
    a = design_auxiliary(b, plan)
    live = LiveModels(b, spec, auxiliary=a)
    _same(live.quality(), b, spec, a)
    tie = np.flatnonzero(b.points.role == 0)
    set_control(b, int(tie[len(tie) // 2]), (0.02, 0.02, 0.02))
    set_control(b, int(np.flatnonzero(b.points.role == 1)[0]), (np.nan, np.nan, np.nan))
    q = live.sync()
    assert len(live._steps) == 2
    _same(q, b, spec, a)


def test_a_failed_new_factorisation_keeps_the_design(monkeypatch):
    """With auxiliary data the datum is left to the factorisation; when the steps run out
    a change factors anew, and a change that leaves no datum must not leave a half-new
    factor behind for the updates after it."""
    plan = FlightDesign(strips=3, images_per_strip=8, control="perimeter",
                        sigma_statoscope=0.3, sigma_apr=0.5)  # fmt: skip
    b, spec = design_block(plan)
    a = design_auxiliary(b, plan)
    live = LiveModels(b, spec, auxiliary=a)
    monkeypatch.setattr(_models_live, "MAX_STEPS", 0)  # every change: a new factorisation
    q0 = live.quality()
    ctrl = np.flatnonzero(b.points.role == 1)
    sig = b.points.sigma[ctrl].copy()
    for j in ctrl:  # planimetric control only: the strips' height offsets are free
        set_control(b, int(j), (0.02, 0.02, np.nan))
    with pytest.raises(NotDeterminableError, match="offsets"):
        live.sync()
    assert live.quality() is q0
    monkeypatch.setattr(_models_live, "MAX_STEPS", 40)  # updates again, on the old factor
    for j, s in zip(ctrl, sig):
        set_control(b, int(j), s)
    assert live.sync() is q0
    tie = np.flatnonzero(b.points.role == 0)
    set_control(b, int(tie[len(tie) // 2]), (0.02, 0.02, 0.02))
    _same(live.sync(), b, spec, a)
