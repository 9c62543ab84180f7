"""The sparse solver of the reduced system: nested dissection and the multifrontal Cholesky.

The factor is checked against a dense solve on random symmetric positive definite
matrices with the block pattern of image networks (a grid of images seeing nearby
points; with and without projection centres for the separators), its separators
against the image graph, and singular systems against the message naming the
parameter where the elimination broke down.
"""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.bundle.reduced import (
    ReducedOptions,
    ReducedStructure,
    dense_matrix,
    factor_reduced,
)
from orientviz.bundle.reduced._choice import choose_solver
from orientviz.bundle.reduced._dissection import check_dissection, nested_dissection
from orientviz.bundle.reduced._multifrontal import NotPositiveDefinite, factor_fronts


def _network(rng, rows: int, cols: int, reach: float = 0.9, n_pt: int = 900):
    """Images on a jittered grid (centres in m), points seen by the images within
    ``reach`` grid units: (obs_cam, obs_pt, m, n_pt, centres)."""
    m = rows * cols
    r, c = np.divmod(np.arange(m), cols)
    xy = np.stack([c, r], 1) + 0.1 * rng.standard_normal((m, 2))
    pts = rng.uniform([-0.5, -0.5], [cols - 0.5, rows - 0.5], (n_pt, 2))
    d = np.hypot(*(pts[:, None, :] - xy[None, :, :]).transpose(2, 0, 1))
    obs_pt, obs_cam = np.nonzero(d <= reach)
    seen = np.bincount(obs_pt, minlength=n_pt) >= 2  # tie points only
    keep = seen[obs_pt]
    _, col = np.unique(obs_pt[keep], return_inverse=True)
    centres = np.column_stack([100.0 * xy, np.full(m, 1000.0)])
    return obs_cam[keep], col, m, int(col.max()) + 1, centres


def _spd_blocks(st: ReducedStructure, rng, scale: float = 1.0) -> np.ndarray:
    """Random blocks on S's pattern making a symmetric positive definite matrix
    (diagonally dominant with a random spread of magnitudes)."""
    blocks = rng.standard_normal((st.n_blocks, 6, 6)) * scale
    d = st.diag_block
    blocks[d] = 0.5 * (blocks[d] + blocks[d].transpose(0, 2, 1))
    row_sum = np.zeros(st.n_cam)
    mags = np.abs(blocks).sum(axis=2).max(axis=1)
    np.add.at(row_sum, st.block_i, mags)
    np.add.at(row_sum, st.block_k, mags)
    blocks[d] += (row_sum + 1.0)[:, None, None] * np.eye(6)
    return blocks


@pytest.mark.parametrize("with_centres", [True, False])
@pytest.mark.parametrize("shape", [(6, 9), (12, 15)])
def test_factor_solves_like_a_dense_cholesky(shape, with_centres):
    rng = np.random.default_rng(7 + shape[0])
    oc, op, m, n_pt, centres = _network(rng, *shape)
    st = ReducedStructure(
        oc, op, m, n_pt, solver="sparse", positions=centres if with_centres else None
    )
    assert st.solver == "sparse" and st.info["fronts"] > 1
    blocks = _spd_blocks(st, rng)
    S = dense_matrix(st, blocks)
    rhs = rng.standard_normal((6 * m, 3))
    expected = np.linalg.solve(S, rhs)
    fac = factor_reduced(st, blocks)
    for got, want in ((fac.solve(rhs), expected), (fac.solve(rhs[:, 1]), expected[:, 1])):
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * np.abs(want).max())
    # the factor is the Cholesky factor: its flops estimate counts the work actually done
    assert st.info["flops"] > 0
    # a second factorisation of other values with the same layout (the arena is reused)
    blocks2 = _spd_blocks(st, rng, scale=3.0)
    x2 = factor_reduced(st, blocks2).solve(rhs[:, 0])
    want2 = np.linalg.solve(dense_matrix(st, blocks2), rhs[:, 0])
    np.testing.assert_allclose(x2, want2, rtol=0, atol=1e-12 * np.abs(want2).max())


@pytest.mark.parametrize("with_centres", [True, False])
def test_separators_separate(with_centres):
    rng = np.random.default_rng(3)
    oc, op, m, n_pt, centres = _network(rng, 14, 20)
    st = ReducedStructure(oc, op, m, n_pt, solver="dense")
    diss = nested_dissection(st.block_i, st.block_k, m, centres if with_centres else None, leaf=8)
    check_dissection(diss, st.block_i, st.block_k)
    assert np.array_equal(np.sort(diss.perm), np.arange(m))
    # below every separator: its children's subtrees share no block of S
    subtree = [set(v.tolist()) for v in diss.pivots]
    kids: list = [[] for _ in diss.pivots]
    for j, q in enumerate(diss.parent.tolist()):
        if q >= 0:
            kids[q].append(j)
            subtree[q] |= subtree[j]  # postorder: children are complete before parents
    owner = {}
    pairs = set(zip(st.block_i.tolist(), st.block_k.tolist()))
    n_split = 0
    for j, ks in enumerate(kids):
        if len(ks) < 2:
            continue
        n_split += 1
        for a in ks:
            for img in subtree[a]:
                owner[img] = a
        for a in ks:
            for b in ks:
                if a < b:
                    assert not any(
                        (min(x, y), max(x, y)) in pairs for x in subtree[a] for y in subtree[b]
                    ), f"separator {j} does not separate its children {a}, {b}"
    assert n_split >= 3
    # separators are small: the top one is a cut across the network, not half of it
    assert diss.pivots[-1].size < m / 5


def test_non_positive_definite_pivot_is_located():
    rng = np.random.default_rng(11)
    oc, op, m, n_pt, centres = _network(rng, 8, 10)
    st = ReducedStructure(oc, op, m, n_pt, solver="sparse", positions=centres)
    blocks = _spd_blocks(st, rng)
    bad_image = int(st.dissection.perm[m // 3])
    blocks[st.diag_block[bad_image], 2, 2] = -1.0e6  # one negative curvature
    with pytest.raises(NotPositiveDefinite) as info:
        factor_fronts(st.fronts, blocks)
    assert info.value.unknown // 6 == bad_image


def test_singular_system_names_the_parameter():
    rng = np.random.default_rng(5)
    oc, op, m, n_pt, centres = _network(rng, 8, 10)
    st = ReducedStructure(oc, op, m, n_pt, solver="sparse", positions=centres)
    blocks = _spd_blocks(st, rng)
    img = 17
    blocks[:, 4, :][st.block_i == img] = 0.0  # nothing determines φ of image 17
    blocks[:, :, 4][st.block_k == img] = 0.0
    blocks[st.diag_block[img], :, 4] = 0.0
    elements = ("X0", "Y0", "Z0", "omega", "phi", "kappa")
    names = [f"image{i}.{e}" for i in range(m) for e in elements]
    # large systems are not diagnosed by a dense null space: the pivot names the parameter
    no_dense = ReducedOptions(dense_diagnosis_limit=0)
    large = ReducedStructure(oc, op, m, n_pt, solver="sparse", positions=centres, options=no_dense)
    with pytest.raises(ov.NotDeterminableError, match=r"broke down at image image17 \(φ\)"):
        factor_reduced(large, blocks, names)
    with pytest.raises(ov.NotDeterminableError) as info:  # small: the null space
        factor_reduced(st, blocks, names)
    assert "image17.phi" in info.value.parameters


def test_auto_takes_the_sparse_factor_for_large_sparse_wide_systems():
    # 40 × 40 images (9600 unknowns > ReducedOptions.dense_max), 8 neighbours each, and no good band:
    # the nested dissection's estimate wins
    side = 40
    m = side * side
    assert 6 * m > ReducedOptions().dense_max
    r, c = np.divmod(np.arange(m), side)
    near = (np.abs(r[:, None] - r[None]) <= 1) & (np.abs(c[:, None] - c[None]) <= 1)
    i, k = np.nonzero(np.triu(near))
    xy = np.column_stack([c, r, np.zeros(m)]).astype(float)
    wide = choose_solver("auto", m, 6 * m - 1, i, k, sparse_estimate=lambda: _estimate(i, k, m, xy))
    assert wide.solver == "sparse"
    assert "sparse" in wide.reason and "dense" not in wide.costs  # too large for dense
    # numbered along the rows the same grid is a narrow band (strips): banded
    narrow = choose_solver("auto", m, 6 * (side + 1) + 5, i, k)
    assert narrow.solver == "banded"


def _estimate(i, k, m, xy):
    d = nested_dissection(i, k, m, xy)
    return d.flops, d.n_nodes
