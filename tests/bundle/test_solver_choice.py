"""The reduced-system solver chosen from the structure, and every path to the same optimum.

A small close-range network (images on a ring around an object, every image seeing most
points: a dense reduced system) and an aerial block (strips: a narrow band) are solved
with every solver and both ways of forming the Schur complement.
"""

from __future__ import annotations

import numpy as np
import pytest
from unordered_networks import close_range_network

import orientviz as ov
from orientviz.bundle import BundleOptions
from orientviz.bundle.problem import BundleProblem, BundleState, point_setup
from orientviz.bundle.reduced._choice import choose_solver, image_blocks


def test_auto_chooses_banded_for_strips_and_dense_for_a_close_range_network():
    aerial = ov.simulate_block(3, 8, rng=2).block
    res = ov.bundle_adjust(aerial, precision=False)
    assert res.solver == "banded"
    assert "narrow band" in res.reduced_info["solver_reason"]
    assert res.reduced_info["formation"] == "pairs"
    block, _ = close_range_network()
    res = ov.bundle_adjust(block, precision=False)
    assert res.solver == "dense" and res.converged
    assert res.reduced_info["solver_reason"].startswith("dense (auto")
    assert res.reduced_info["formation"] == "dense"


def _network(name: str, strips: int):
    """The close-range network 5 cm / 5 mrad off, or an aerial block of ``strips`` strips."""
    if name == "aerial":
        return ov.simulate_block(strips, 6, rng=4).block
    return close_range_network(start_error=0.05)[0]


@pytest.mark.parametrize("network", ["close-range", "aerial"])
def test_every_solver_reaches_the_same_optimum(network):
    block = _network(network, 3)
    ref = ov.bundle_adjust(block, precision=False, solver="dense")
    assert ref.converged
    auto = {"close-range": "dense", "aerial": "banded"}[network]
    for solver in ("banded", "sparse", "auto"):
        res = ov.bundle_adjust(block, precision=False, solver=solver)
        assert res.solver == (auto if solver == "auto" else solver)
        assert res.iterations == ref.iterations
        # the same linear systems factored differently: the same optimum to rounding
        np.testing.assert_allclose(res.x, ref.x, rtol=0, atol=1e-9 * np.abs(ref.x).max())
        assert res.sigma0 == pytest.approx(ref.sigma0, rel=1e-10)


@pytest.mark.parametrize("network", ["close-range", "aerial"])
def test_dense_and_pairwise_schur_complements_agree(network):
    block = _network(network, 2)
    prob = BundleProblem(block, point_setup(block, "fixed"), options=BundleOptions(solver="dense"))
    st = BundleState(block.images.X0, block.images.angles, block.points.xyz, np.zeros(0))
    rw, Je, Jp = prob.residuals(st, jac=True)
    out = {}
    for formation in ("pairs", "dense"):
        prob.reduced.formation = formation
        ne = prob.normal(st, rw, Je, Jp, lam=0.1)
        assert (ne.S is not None) == (formation == "dense")
        out[formation] = (ne.blocks, prob.solve(ne, prob.names()[: 6 * prob.m])[0])
    scale = np.abs(out["pairs"][0]).max()
    np.testing.assert_allclose(out["dense"][0], out["pairs"][0], rtol=0, atol=1e-12 * scale)
    dc = out["pairs"][1]
    np.testing.assert_allclose(out["dense"][1], dc, rtol=0, atol=1e-9 * np.abs(dc).max())
    # each block really is S = U − Σ W V⁻¹ Wᵀ: the diagonal blocks are symmetric
    # and S is positive definite (a transposed or misplaced block would break both)
    diag = out["dense"][0][prob.reduced.diag_block]
    np.testing.assert_allclose(diag, diag.transpose(0, 2, 1), rtol=0, atol=1e-12 * scale)


def test_solver_choice_from_structure_alone():
    m = 400
    # a grid of 20 × 20 images, each overlapping its 8 neighbours, numbered row by row
    r, c = np.divmod(np.arange(m), 20)
    i, k = np.nonzero((np.abs(r[:, None] - r[None]) <= 1) & (np.abs(c[:, None] - c[None]) <= 1))
    keep = i <= k
    bi, bk = i[keep], k[keep]
    narrow = choose_solver("auto", m, 6 * 21 + 5, bi, bk)
    assert narrow.solver == "banded"
    # the same grid with a band as wide as the system (no good numbering found): a sparse
    # factor with a fill-reducing ordering is estimated far cheaper than dense
    wide = choose_solver("auto", m, 6 * m - 1, bi, bk)
    assert wide.solver == "sparse"
    assert wide.costs["sparse"] < wide.costs["dense"]
    # a complete graph (every image with every other): dense
    i, k = np.triu_indices(60)
    assert choose_solver("auto", 60, 6 * 60 - 1, i, k).solver == "dense"
    assert choose_solver("dense", 60, None, i, k).reason == "dense (requested)"
    assert choose_solver("sparse", 60, None, i, k).reason == (
        "sparse (requested, nested-dissection multifrontal Cholesky)"
    )
    with pytest.raises(ValueError, match="solver"):
        choose_solver("splu", 60, None, i, k)


def test_image_blocks_are_the_pairs_of_images_sharing_a_point():
    cam = np.array([0, 1, 2, 2, 3, 0, 3])
    pt = np.array([0, 0, 0, 1, 1, -1, 2])  # ray 5: a fixed point (no coupling)
    bi, bk, n_pairs = image_blocks(cam, pt, 5, 3)
    got = set(zip(bi.tolist(), bk.tolist()))
    assert got == {(0, 0), (1, 1), (2, 2), (3, 3), (4, 4), (0, 1), (0, 2), (1, 2), (2, 3)}
    assert n_pairs == 6 + 3 + 1  # k(k + 1)/2 for tracks of 3, 2, 1 rays


@pytest.mark.parametrize("seed", [0, 1])
def test_image_blocks_dense_and_sparse_products_give_the_same_pattern(monkeypatch, seed):
    from orientviz.bundle.reduced import _choice

    rng = np.random.default_rng(seed)
    m, n_pt = 30, 400
    ks = rng.integers(1, 7, n_pt)
    cam = np.concatenate([rng.choice(m, k, replace=False) for k in ks])
    pt = np.repeat(np.arange(n_pt), ks)
    pt[rng.random(pt.size) < 0.05] = -1  # rays of fixed points couple nothing
    got = {}
    for name, per_pair in (("dense", np.inf), ("sparse", 1e-300)):
        monkeypatch.setattr(_choice, "DENSE_PATTERN_FLOPS_PER_PAIR", per_pair)
        got[name] = image_blocks(cam, pt, m, n_pt)
    var = pt >= 0
    keys = {
        (min(a, b), max(a, b))
        for j in range(n_pt)
        for a in cam[var][pt[var] == j]
        for b in cam[var][pt[var] == j]
    } | {(i, i) for i in range(m)}
    k = np.bincount(pt[var], minlength=n_pt)
    for bi, bk, n_pairs in got.values():
        assert set(zip(bi.tolist(), bk.tolist())) == keys
        assert n_pairs == int(np.sum(k * (k + 1) // 2))
    np.testing.assert_array_equal(got["dense"][0], got["sparse"][0])
    np.testing.assert_array_equal(got["dense"][1], got["sparse"][1])


def test_precision_is_the_same_whatever_solved_and_formed_the_reduced_system():
    block, _ = close_range_network(start_error=0.05)
    dense = ov.bundle_adjust(block)  # S formed densely, Q_cp from the dense inverse
    assert dense.solver == "dense" and dense.reduced_info["formation"] == "dense"
    banded = ov.bundle_adjust(block, solver="banded")  # pairs of rays, selected inverse
    assert banded.reduced_info["formation"] == "pairs"
    np.testing.assert_allclose(dense.std(), banded.std(), rtol=1e-8)
    np.testing.assert_allclose(
        dense.redundancy_numbers, banded.redundancy_numbers, rtol=0, atol=1e-10
    )
    np.testing.assert_allclose(dense.ray_gains.points, banded.ray_gains.points, rtol=1e-7)
    for name in ("exterior", "points"):
        a, b = dense.cofactor_groups[name], banded.cofactor_groups[name]
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 * np.abs(b).max())


@pytest.mark.parametrize(
    "m, n_pt, n_pairs, want",
    [
        (23, 1443, 17683, "pairs"),  # COLMAP bart: dense 3.3 ms, pairs 1.9 ms per formation
        (16, 22106, 253764, "pairs"),  # BAL 16-22106: dense 49 ms, pairs 25 ms
        (177, 4217, 3627841, "dense"),  # COLMAP soft (long tracks): dense 352 ms, pairs 873 ms
    ],
)
def test_formation_follows_the_measured_costs(m, n_pt, n_pairs, want):
    """The cost model picks the formation that was faster on real models (1 BLAS thread;
    benchmarks/README.md, session 14); a banded or sparse S is always formed by pairs."""
    from orientviz.bundle.reduced._choice import choose_formation

    assert choose_formation("dense", m, n_pt, n_pairs) == want
    assert choose_formation("banded", m, n_pt, n_pairs) == "pairs"
