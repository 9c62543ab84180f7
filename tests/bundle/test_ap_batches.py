"""A group of additional parameters per image: the border's point terms by point batches.

With a group per image (as a BAL problem has) a point's rays couple as many groups as it
has rays; E's other-group blocks and F's correction are then formed by stacked
per-point products (``bundle.problem._ap_batches``) instead of one product per group
pair. Both ways are checked against the textbook reference's optimum, and against
each other.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_reference import assert_same_optimum, one_blas_thread  # noqa: F401

import orientviz as ov
import orientviz.bundle.problem._ap_normal as ap_normal_module
import orientviz.bundle.problem._problem as problem_module
from orientviz.bundle.reference import reference_bundle

CASE = dict(additional="brown", ap_sigma=50.0)


@pytest.fixture(scope="module")
def per_image():
    """3 × 6 images whose observations carry a radial distortion, a group per image."""

    def systematic(xy, img):
        r2 = (xy**2).sum(axis=1, keepdims=True)
        return 2e-8 * r2 * xy  # mm: a few µm at the image corners

    block = ov.simulate_block(3, 6, rng=4, extra=None, systematic=systematic).block
    group = np.arange(block.n_images)
    return block, group, reference_bundle(block, tol=1e-8, max_iter=60, ap_group=group, **CASE)


def _solve(block, group):
    return ov.bundle_adjust(block, solver="dense", tol=1e-10, max_iter=80, precision=False,
                            ap_group=group, **CASE)  # fmt: skip


def test_the_point_batches_reach_the_reference_optimum(per_image, monkeypatch):
    block, group, ref = per_image
    calls = []
    real = ap_normal_module.batched_terms
    monkeypatch.setattr(ap_normal_module, "batched_terms", lambda *a: calls.append(1) or real(*a))
    res = _solve(block, group)
    assert calls, "the per-image groups did not take the batched path"
    assert_same_optimum(res, ref, block)


def _formation(per_image, monkeypatch):
    """The arguments of one formation of the border (E, F formed, not reused) in a short
    run, and the formation function itself."""
    block, group, _ = per_image
    calls = []
    real = problem_module.ap_normal
    monkeypatch.setattr(problem_module, "ap_normal", lambda *a: calls.append(a) or real(*a))
    ov.bundle_adjust(block, max_iter=2, precision=False, ap_group=group, **CASE)
    return next(a for a in calls if a[-1] is None), real


def test_the_point_batches_equal_the_products_per_group_pair(per_image, monkeypatch):
    # one formation of the border, the same inputs: by point batches and per group pair
    args, real = _formation(per_image, monkeypatch)
    A = args[0].ap.structure
    batched = real(*args)
    A.batches = None
    per_pair = real(*args)
    for x, y in ((batched.E_border.dense(), per_pair.E_border.dense()), (batched.F0, per_pair.F0)):
        assert np.max(np.abs(x - y)) < 1e-12 * np.max(np.abs(y))
    assert np.array_equal(batched.ba, per_pair.ba)


def test_row_indices_formed_per_call_give_the_kept_ones_sums(per_image, monkeypatch):
    # a model whose row indices are too large to keep forms them in each formation
    args, real = _formation(per_image, monkeypatch)
    A = args[0].ap.structure
    kept = real(*args)
    A.batches = [b._replace(e_rows=None, f_rows=None) for b in A.batches]
    formed = real(*args)
    assert np.array_equal(kept.E_border.dense(), formed.E_border.dense())
    assert np.array_equal(kept.F0, formed.F0)


def test_a_batch_map_adds_every_block_once(per_image, monkeypatch):
    # every (ray, other pair) block row and every (pair, pair) block row lands in
    # exactly one row of E's or F's blocks
    block, group, _ = per_image
    seen = []
    real = ap_normal_module.batched_terms
    monkeypatch.setattr(
        ap_normal_module, "batched_terms", lambda A, *a: seen.append(A) or real(A, *a)
    )
    ov.bundle_adjust(block, max_iter=3, precision=False, ap_group=group, **CASE)
    A = seen[0]
    K, G = A.e_key.size, A.G
    e_block = np.concatenate([b.e_block.reshape(-1) for b in A.batches])
    f_block = np.concatenate([b.f_block.reshape(-1) for b in A.batches])
    k = A.F_direct.shape[1]  # parameters per group
    assert all(b.e_rows is not None for b in A.batches)  # a small problem keeps its rows
    for b in A.batches:  # a block's rows are 6·block + 0…5 (E), k·block + 0…k−1 (F)
        n, kr = b.rays.shape
        c = b.pairs.shape[1]
        e = b.e_rows.reshape(n, kr, 6, c)
        assert np.array_equal(e, 6 * b.e_block[:, :, None, :] + np.arange(6)[:, None])
        f = b.f_rows.reshape(n, c, k, c)
        assert np.array_equal(f, k * b.f_block[:, :, None, :] + np.arange(k)[:, None])
    # E: one (ray, other pair) block at a time into the block of its (image, group) key
    kept = e_block[e_block < K]
    per_key = np.bincount(np.searchsorted(A.e_key, A._e_rows), minlength=K)
    assert np.array_equal(np.bincount(kept, minlength=K), per_key)
    assert kept.size == A.e_obs.size
    # F: one (pair, pair) block of one point into (g_e, g_e'): as many as such pairs
    per_group_pair = np.bincount(A.f_key.repeat(np.diff(A.f_bounds)), minlength=G * G)
    assert np.array_equal(np.bincount(f_block, minlength=G * G), per_group_pair)


def test_a_small_dense_system_forms_the_border_exactly(per_image, monkeypatch):
    """A dense S with a group per image: Fs formed exactly in every step (no conjugate
    gradients), the same optimum as the conjugate gradients' path and the reference."""
    import orientviz.bundle.problem._border as border_module

    block, group, ref = per_image
    exact = _solve(block, group)
    assert set(exact.reduced_info["ap_border"]) - {"held"} == {"Fs formed (dense S)"}
    assert_same_optimum(exact, ref, block)
    monkeypatch.setattr(border_module, "DENSE_EXACT_MAX", 0.0)
    cg = _solve(block, group)
    assert any(s.startswith("cg") for s in cg.reduced_info["ap_border"])
    assert_same_optimum(cg, ref, block)
