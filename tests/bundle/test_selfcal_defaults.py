"""self_calibrate's defaults follow the camera (issue #20 point 3): a 7 mm phone-size
camera and a 150 mm aerial-size camera with the same call."""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.bundle._selfcal import camera_defaults, default_ap_sigma, default_set
from orientviz.simulate import simulate_block, simulate_calibration

CASES = {
    "phone": (7.3, (7.2, 5.4), {"c": 7.32, "x0": 0.02, "K1": 4e-3, "K2": -4e-5, "P1": -6e-5}, 3e-4),
    "aerial": (150.0, (230.0, 230.0), {"c": 150.05, "x0": 0.01, "K1": 3e-8, "K2": -1e-12,
                                       "P1": 2e-7}, 2e-3),
}  # fmt: skip


@pytest.mark.parametrize("case", list(CASES))
def test_the_same_call_calibrates_a_phone_and_an_aerial_camera(case):
    c, fmt, truth, sigma = CASES[case]
    sim = simulate_calibration(np.random.default_rng(11), c=c, format_mm=fmt, camera=truth,
                               sigma_mm=sigma)  # fmt: skip
    sc = ov.self_calibrate(sim.block, "backward", max_iter=50)
    assert set(truth) <= set(sc.kept)  # every real term kept, K2 despite ρ(K1, K2) ≈ −0.96
    for name, value in truth.items():
        est, s = sc.adjustment.camera.get(name)
        assert abs(est - value) < 3 * s, (name, est, value, s)
    # what was dropped is said, with the test statistic
    assert sc.reasons and all("not significant (largest t = " in r for r in sc.reasons.values())
    assert any("K1~K2" in p for p in sc.correlated)
    assert "K1~K2" in sc.summary()


def test_aerial_defaults_are_the_old_numbers_and_phone_defaults_scale():
    aerial = simulate_block(1, 4, rng=1).block
    assert camera_defaults(aerial)["side"] == 230.0
    assert default_set("ebner12", aerial).b == pytest.approx(92.0)
    assert default_ap_sigma(default_set("ebner12", aerial), aerial) == pytest.approx(10.0)
    phone = simulate_calibration(np.random.default_rng(1)).block
    d = camera_defaults(phone)
    assert d["c"] == 7.3 and 1.0 < d["r0"] < 3.6  # r0 follows the image points, not 100 mm
    brown = default_set("brown", phone)
    assert (brown.c, brown.r0) == (7.3, d["r0"])
    assert default_ap_sigma(default_set("backward", phone), phone) == pytest.approx(100 * d["r0"])
