"""Quality measures per image and point (no viser): values, ordering, colours, legend."""

import numpy as np
import pytest

import orientviz as ov
from orientviz.viewer.quality import MEASURES, colour_bar, compute_quality, legend_text


@pytest.fixture
def adjusted(block):
    block.observations.xy += np.random.default_rng(4).normal(0, 0.004, block.observations.xy.shape)
    block.observations.xy[3] += [0.03, 0.0]  # one blunder of 30 µm
    return block, ov.bundle_adjust(block)


def test_rms_and_max_w_per_image_match_a_direct_computation(adjusted):
    block, res = adjusted
    n = block.n_observations
    w = res.normalized_residuals[: 2 * n].reshape(n, 2)
    rms = compute_quality(block, res, "rms_w")
    mx = compute_quality(block, res, "max_w")
    for i in range(block.n_images):
        wi = w[block.observations.image == i]
        assert rms.image[i] == pytest.approx(np.sqrt(np.nanmean(wi**2)), rel=1e-12)
        assert mx.image[i] == pytest.approx(np.nanmax(np.abs(wi)), rel=1e-12)
    # the worst image and point are those of the largest |w|
    j = int(np.argmax(np.where(np.isnan(w), -1.0, np.abs(w)).max(axis=1)))
    assert mx.worst("image", 1)[0] == block.observations.image[j]
    assert mx.worst("point", 1)[0] == block.observations.point[j]


def test_redundancy_share_and_std(adjusted):
    block, res = adjusted
    n = block.n_observations
    r = res.redundancy_numbers[: 2 * n].reshape(n, 2)
    q = compute_quality(block, res, "redundancy")
    k = int(block.observations.point[0])
    assert q.point[k] == pytest.approx(np.nanmean(r[block.observations.point == k]), rel=1e-12)
    assert np.all((q.image >= 0) & (q.image <= 1))
    assert not q.worse_high
    worst = q.worst("point", 3)
    assert np.all(np.diff(q.point[worst]) >= 0)  # smallest redundancy first
    s = compute_quality(block, res, "std")
    Q = res.cofactor_groups["points"][k]
    assert s.point[k] == pytest.approx(res.sigma0 * np.sqrt(np.trace(Q) / 3), rel=1e-12)
    fixed = block.points.role == 1
    assert np.all(s.point[fixed] == 0)  # fixed control: no uncertainty
    assert np.all(s.image > 0) and s.unit == "m"


def test_no_result_gives_grey_and_nan(adjusted):
    block, _ = adjusted
    q = compute_quality(block, None, "rms_w")
    assert np.all(np.isnan(q.image)) and q.worst("image").size == 0
    assert np.all(q.colours(q.image) == 150)  # grey
    assert "not available (6 images" in legend_text(q)


def test_colours_run_from_good_to_bad(adjusted):
    block, res = adjusted
    for key in MEASURES:
        q = compute_quality(block, res, key)
        good, bad = q.ticks(2)
        cg, cb = q.colours(np.array([good, bad])).astype(int)
        assert cb[0] > cg[0] + 100, key  # bad is red
        bar = colour_bar(q)
        assert bar.shape == (14, 240, 3) and bar.dtype == np.uint8
        good_rgb = q.colours(np.array([good]))[0].astype(int)
        np.testing.assert_allclose(bar[7, 1].astype(int), good_rgb, atol=2)  # left end: good
