"""Pieces of the bundle's normal equations: the images' Gram matrices (padded stack or
per image) and the sums over a point's rays."""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.bundle.reduced import ImageGram
from orientviz.bundle.reduced._structure import _segments
from orientviz.bundle.reduced._tracks import SUM_BY_ADDS_MAX_K, _sum_rays


@pytest.mark.parametrize("pad_max", [0.5, 0.0])
def test_image_grams_are_the_sums_over_each_images_rays(pad_max):
    rng = np.random.default_rng(3)
    m = 7
    image = rng.permutation(np.repeat(np.arange(m), [10, 9, 11, 8, 0, 12, 10]))  # image 4: none
    n = image.size
    layout = ImageGram(*_segments(image, m), m, n, pad_max=pad_max)
    assert (layout.slots is None) == (pad_max == 0.0)
    J = rng.standard_normal((n, 2, 7))
    Jz = np.concatenate([J, np.zeros((1, 2, 7))])
    want = np.zeros((m, 7, 7))
    for i in range(m):
        A = J[image == i].reshape(-1, 7)
        want[i] = A.T @ A
    np.testing.assert_allclose(layout.grams(Jz), want, rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("pad_max", [0.5, 0.0])
def test_the_grams_rays_by_image_are_each_images_rays_in_order(pad_max):
    # what the border's own-group E blocks read instead of gathering J_e again
    rng = np.random.default_rng(4)
    m = 6
    image = rng.permutation(np.repeat(np.arange(m), [7, 0, 9, 5, 11, 6]))  # image 1: none
    n = image.size
    layout = ImageGram(*_segments(image, m), m, n, pad_max=pad_max)
    assert (layout.slots is None) == (pad_max == 0.0)
    Jz = np.concatenate([rng.standard_normal((n, 2, 7)), np.zeros((1, 2, 7))])
    rays = []
    G = layout.grams(Jz, rays)
    np.testing.assert_array_equal(G, layout.grams(Jz))
    got = rays[0].of_images()
    assert [i for i, _ in got] == [0, 2, 3, 4, 5]
    for i, R in got:
        np.testing.assert_array_equal(R, Jz[:n][image == i].reshape(-1, 7))


@pytest.mark.parametrize("k", [1, 2, 3, SUM_BY_ADDS_MAX_K, SUM_BY_ADDS_MAX_K + 1])
def test_sums_over_a_points_rays_equal_numpys(k):
    X = np.random.default_rng(k).standard_normal((11, k, 3, 3))
    np.testing.assert_array_equal(_sum_rays(X), X.sum(axis=1))


def test_couplings_and_back_substitution_sums_per_point_equal_the_per_ray_ones():
    import orientviz as ov
    from orientviz.bundle.problem import BundleProblem, point_setup
    from orientviz.bundle.reduced import point_sums_wt, ray_couplings

    sim = ov.simulate_block(3, 6, rng=2)
    tg = BundleProblem(sim.block, point_setup(sim.block, "fixed")).reduced.tracks
    rng = np.random.default_rng(5)
    nv, p = tg.rays.size, tg.points.size
    W, Vinv = rng.standard_normal((nv, 6, 3)), rng.standard_normal((p, 3, 3))
    dc = rng.standard_normal((sim.block.n_images, 6))
    assert len({k for k, _, _ in tg.groups}) > 1  # several track lengths
    np.testing.assert_allclose(ray_couplings(tg, W, Vinv), W @ Vinv[tg.ray_point], rtol=1e-14)
    want = np.zeros((p, 3))
    np.add.at(want, tg.ray_point, np.einsum("nij,ni->nj", W, dc[tg.ray_image]))
    np.testing.assert_allclose(point_sums_wt(tg, W, dc), want, rtol=1e-12, atol=1e-12)


def test_the_rays_track_order_by_two_radix_sorts_is_lexsorts():
    # rays by (track length, point unknown), then image, then their order; fixed points' last
    from orientviz.bundle.problem._parts import _track_order

    rng = np.random.default_rng(11)
    for _ in range(50):
        n_var, m, n = int(rng.integers(1, 200)), int(rng.integers(1, 30)), int(rng.integers(1, 900))
        col = rng.integers(-1, n_var, n)
        var = col >= 0
        oi = rng.integers(0, m, n)
        k = np.bincount(col[var], minlength=n_var)
        key = np.where(var, k[np.where(var, col, 0)] * n_var + col, np.iinfo(np.int64).max)
        np.testing.assert_array_equal(_track_order(k, col, var, oi, m), np.lexsort((oi, key)))
