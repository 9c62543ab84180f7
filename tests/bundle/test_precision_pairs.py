"""The image–point cofactors by pairs of rays (orientviz.bundle.precision._pairs) against
the per-pair formula: one (d × d)(d × 3) product per pair of rays of a point, summed per
ray by ``np.add.reduceat`` — the same numbers to the last bit."""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.bundle.precision import _pairs
from orientviz.bundle.reduced import ReducedStructure


@pytest.mark.parametrize("k", [1, 2, 3, 7, 8, 9, 16, 17, 128, 129, 130, 300, 301])
def test_segment_sum_adds_as_reduceat(k):
    rng = np.random.default_rng(k)
    # magnitudes over many decades: a different order of the additions shows in the bits
    X = rng.standard_normal((5, k, 4, 3)) * 10.0 ** rng.integers(-8, 9, (5, k, 4, 3))
    X[0, :, 0, 0] = -0.0  # a sum of negative zeros stays −0.0 (numpy starts from −0.0)
    want = np.add.reduceat(X.reshape(-1, 4, 3), np.arange(0, 5 * k, k), axis=0)
    got = _pairs.segment_sum(X)
    assert got.tobytes() == want.tobytes()


def _network(rng, m, n_pt, rays_per_point, repeat_image=False):
    """Observations (image, point) of n_pt points seen in random images; with
    ``repeat_image`` the third point (three rays) has two in one image."""
    oc, op = [], []
    for j in range(n_pt):
        k = int(rays_per_point[j % len(rays_per_point)])
        imgs = rng.choice(m, size=k, replace=False)
        if repeat_image and j == 2:
            imgs[1] = imgs[0]
        oc += imgs.tolist()
        op += [j] * k
    oc, op = np.array(oc), np.array(op)
    fixed = rng.choice(m, size=3)  # rays of a fixed point (−1): no Q_cp
    order = rng.permutation(oc.size + 3)
    return np.r_[oc, fixed][order], np.r_[op, [-1, -1, -1]][order]


def _per_pair(S, Zblk, T, n):
    """Q_cp by the formula: for each ray a of a point, the product Q(i_a, i_b) T_b with
    each ray b of its point (the stored block, or the transpose of block (i_b, i_a)),
    summed by ``np.add.reduceat`` over b in the point's ray order."""
    m = S.n_cam
    keys = list(S.block_i * m + S.block_k)
    Q = np.zeros((n, Zblk.shape[1], 3))
    starts = np.append(S.pt_starts, S.pt_obs.size)
    for j in range(S.n_pt):
        rays = S.pt_obs[starts[j] : starts[j + 1]]
        for a in rays:
            prods = []
            for b in rays:
                ia, ib = S.obs_cam[a], S.obs_cam[b]
                blk = Zblk[keys.index(min(ia, ib) * m + max(ia, ib))]
                prods.append((blk.T if ia > ib else blk) @ T[b])
            Q[a] = -np.add.reduceat(np.stack(prods), [0], axis=0)[0]
    return Q


@pytest.mark.parametrize("d", [6, 9])
@pytest.mark.parametrize("full", [True, False])
def test_cofactors_by_pairs_equal_the_per_pair_formula(d, full, monkeypatch):
    if not full:  # the blocks found by a search in the structure's keys
        monkeypatch.setattr(_pairs, "FULL_PAIRS_DOUBLES", 0)
    # small chunks: the points of one track length split over several
    monkeypatch.setattr(_pairs, "PAIR_CHUNK_DOUBLES", 4 * d * d)
    rng = np.random.default_rng(d)
    m = 14
    oc, op = _network(rng, m, 60, [1, 2, 3, 5, 9, 12], repeat_image=True)
    S = ReducedStructure(oc, op, m, 60, solver="dense")
    Zblk = rng.standard_normal((S.n_blocks, d, d))  # not symmetric: a wrong transpose shows
    T = rng.standard_normal((oc.size, d, 3))
    got = np.full((oc.size, d, 3), np.nan)
    got[op < 0] = 0.0
    _pairs.cofactors_by_pairs(S, Zblk, T, got)
    want = _per_pair(S, Zblk, T, oc.size)
    assert got.tobytes() == want.tobytes()


def test_point_cofactors_equal_the_per_point_formula():
    rng = np.random.default_rng(7)
    m, d = 12, 6
    oc, op = _network(rng, m, 40, [2, 3, 4, 11])
    S = ReducedStructure(oc, op, m, 40, solver="dense")
    T = rng.standard_normal((oc.size, d, 3))
    Qcp = rng.standard_normal((oc.size, d, 3))
    Vinv = rng.standard_normal((40, 3, 3))
    got = _pairs.point_cofactors(Vinv, T, Qcp, S)
    # per point j in point order: V_j⁻¹ + Σ_b T_bᵀ (−Q_cp,b) by np.add.reduceat
    vo = S.pt_obs
    want = Vinv + np.add.reduceat(T[vo].transpose(0, 2, 1) @ (-Qcp[vo]), S.pt_starts, axis=0)
    assert got.tobytes() == want.tobytes()


def test_var_rows_are_the_rays_of_point_unknowns():
    class Obs:
        column = np.array([3, 0, 2, -1, -1])

    assert _pairs.var_rows(Obs) == slice(0, 3)
    Obs.column = np.array([3, -1, 2, 0, -1])
    np.testing.assert_array_equal(_pairs.var_rows(Obs), [0, 2, 3])


@pytest.mark.parametrize("border", [False, True])
@pytest.mark.parametrize("d", [6, 9])
def test_ray_cofactors_equal_the_three_steps(d, border, monkeypatch):
    """The one-pass Q_pp, gains and 2 × 2 blocks equal Q_cp by pairs, Q_pp per point and
    the rays' blocks formed one after the other (rays of fixed points included; with a
    border's terms subtracted from Q_cp and Q_pp in between)."""
    from orientviz.bundle.precision._store import ray_blocks

    monkeypatch.setattr(_pairs, "PAIR_CHUNK_DOUBLES", 4 * d * d)
    rng = np.random.default_rng(11)
    m, n_pt = 14, 50
    oc, op = _network(rng, m, n_pt, [1, 2, 3, 6, 10], repeat_image=True)
    S = ReducedStructure(oc, op, m, n_pt, solver="dense")
    n = oc.size
    Zblk = rng.standard_normal((S.n_blocks, d, d))
    T = rng.standard_normal((n, d, 3))
    T[op < 0] = 0.0
    Vinv = rng.standard_normal((n_pt, 3, 3))
    Qimg = rng.standard_normal((m, d, d))
    Jc, Jp = rng.standard_normal((n, 2, d)), rng.standard_normal((n, 2, 3))
    dQcp = rng.standard_normal((n, d, 3)) if border else None
    dQpp = rng.standard_normal((n_pt, 3, 3)) if border else None
    got = _pairs.ray_cofactors(S, Zblk, T, Vinv, Qimg, oc, Jc, Jp, dQcp, dQpp)
    Qcp = np.zeros((n, d, 3))
    _pairs.cofactors_by_pairs(S, Zblk, T, Qcp)
    vo = np.flatnonzero(op >= 0)
    if border:
        Qcp[vo] -= dQcp[vo]
    Qpp = _pairs.point_cofactors(Vinv, T, Qcp, S)
    if border:
        Qpp -= dQpp
    want = (Qpp, *ray_blocks(Qimg, oc, Qcp, Qpp, Jc, Jp[vo], vo, op[vo]))
    for g, w in zip(got, want, strict=True):
        assert g.tobytes() == w.tobytes()


@pytest.mark.parametrize("d", [6, 7, 9, 16, 18])
def test_ray_blocks_equal_their_products_on_the_transposed_views(d):
    """ray_blocks multiplies by contiguous copies of the transposed designs for short
    products (faster; _store.fast_layout), by the views beyond: each gain and 2 × 2 block
    equals the same products on the transposed views within the rounding bound of sums
    over d + 3 terms, and to the last bit where this machine's BLAS adds short products in
    one order in both layouts (the OpenBLAS measured, benchmarks/README.md; another BLAS
    or CPU may add in another order)."""
    from orientviz.bundle.precision._store import LAYOUT_FREE_TERMS, ray_blocks

    rng = np.random.default_rng(d)
    m, n, p = 7, 400, 90

    def wide(*shape):  # magnitudes over many decades: another order of sums shows
        return rng.standard_normal(shape) * 10.0 ** rng.integers(-6, 7, shape)

    img, pcol = rng.integers(0, m, n), rng.integers(0, p, n)
    Qimg, Qcp, Qpp = wide(m, d, d), wide(n, d, 3), wide(p, 3, 3)
    Jc = wide(n + 1, 2, d + 1)[:n, :, :d]  # a strided view, as the camera blocks hand it
    Jp = wide(n, 2, 3)
    vo = np.flatnonzero(rng.random(n) < 0.8)
    JcT, JpT = Jc.transpose(0, 2, 1), Jp[vo].transpose(0, 2, 1)
    Kc = Qimg[img] @ JcT
    Kc[vo] += Qcp[vo] @ JpT
    Kp = np.zeros((n, 3, 2))
    Kp[vo] = Qcp[vo].transpose(0, 2, 1) @ JcT[vo] + Qpp[pcol[vo]] @ JpT
    H = Jc @ Kc
    H[vo] += Jp[vo] @ Kp[vo]
    got = ray_blocks(Qimg, img, Qcp, Qpp, Jc, Jp[vo], vo, pcol[vo])
    # the same products on absolute values bound every rounding difference (Higham's γ)
    aQ, aC, aP, aJc, aJp = (np.abs(a) for a in (Qimg, Qcp, Qpp, Jc, Jp))
    aKc = aQ[img] @ aJc.transpose(0, 2, 1)
    aKc[vo] += aC[vo] @ aJp[vo].transpose(0, 2, 1)
    aKp = np.zeros((n, 3, 2))
    aKp[vo] = aC[vo].transpose(0, 2, 1) @ aJc[vo].transpose(0, 2, 1) + aP[pcol[vo]] @ aJp[
        vo
    ].transpose(0, 2, 1)
    aH = aJc @ aKc
    aH[vo] += aJp[vo] @ aKp[vo]
    gamma = 4 * (d + 3) * np.finfo(float).eps
    for g, w, a in zip(got, (Kc, Kp, H), (aKc, aKp, aH), strict=True):
        assert g.shape == w.shape and np.all(np.abs(g - w) <= gamma * a)
    # the views beyond LAYOUT_FREE_TERMS are the reference's own products: the same bits on
    # any machine; below it, the copies may not change a single bit where this BLAS adds a
    # short product's terms in one order in both layouts (OpenBLAS here)
    probe_a, probe_b = wide(n, 2, d), wide(n, 2, d).transpose(0, 2, 1)
    copied = probe_a @ np.ascontiguousarray(probe_b)
    if d >= LAYOUT_FREE_TERMS or (probe_a @ probe_b).tobytes() == copied.tobytes():
        for g, w in zip(got, (Kc, Kp, H), strict=True):
            assert g.tobytes() == w.tobytes()
