"""The radar widget draws its discrepancy arrows at a visible, round exaggeration."""

import numpy as np

from orientviz.widgets.radar import RadarSliders, arrow_scale


def test_arrows_are_a_visible_share_of_the_image():
    state = RadarSliders("fig7", 2)
    state.set("X0", state.values["X0"] + 300.0)
    xy, d = state.image_coordinates(), state.discrepancies()
    k = arrow_scale(xy, d)
    longest = k * np.linalg.norm(d, axis=1).max()
    extent = np.ptp(xy, axis=0).max()
    assert 0.05 * extent <= longest <= 0.12 * extent
    assert k / 10 ** np.floor(np.log10(k)) in (1.0, 2.0, 5.0)


def test_no_discrepancy_gives_factor_one():
    xy = np.array([[0.0, 0.0], [10.0, 5.0]])
    assert arrow_scale(xy, np.zeros_like(xy)) == 1.0
