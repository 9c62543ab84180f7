"""Single-precision band factor with double-precision refinement (bundle._mixed_band)."""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
import orientviz.bundle._mixed_band as mixed
import orientviz.bundle._reduced as reduced
from orientviz.bundle import BundleProblem, BundleState, factor_reduced, point_setup


def _reduced_system(strips=3, n=8, seed=5):
    """S's blocks of a simulated strip block at its start values, and its structure."""
    sim = ov.simulate_block(strips, n, rng=seed, extra=8, control="perimeter")
    block = sim.block
    prob = BundleProblem(block, point_setup(block, "fixed"), solver="banded")
    st = BundleState(
        block.images.X0.copy(), block.images.angles.copy(), block.points.xyz.copy(), np.zeros(0)
    )
    rw, Je, Jp = prob.residuals(st, jac=True)
    ne = prob.normal(st, rw, Je, Jp)
    return prob.reduced, ne.blocks.copy(), ne.rhs.copy()


def _dense(st, blocks):
    return reduced.dense_matrix(st, blocks)


def test_block_sparse_s_equals_the_dense_s():
    st, blocks, rhs = _reduced_system()
    S = mixed.SymmetricBlocks(st.block_i, st.block_k, st.n_cam).matrix(blocks)
    D = _dense(st, blocks)
    np.testing.assert_array_equal(S.toarray(), D)
    np.testing.assert_allclose(S @ rhs, D @ rhs, rtol=1e-13, atol=1e-13 * np.abs(D @ rhs).max())


@pytest.fixture
def always_single(monkeypatch):
    monkeypatch.setattr(reduced, "MIN_BAND_FLOPS", 0.0)


def test_refined_solves_equal_the_double_precision_solve(always_single):
    st, blocks, rhs = _reduced_system()
    fac = factor_reduced(st, blocks.copy(), single=True)
    assert fac.kind == "mixed"
    ref = np.linalg.solve(_dense(st, blocks), rhs)
    got = fac.solve(rhs)
    assert fac.data.fallback is None and 1 <= fac.data.rounds[-1] <= mixed.MAX_ROUNDS
    # as good as a double-precision step for the bundle: within 1e-6 of its largest element
    assert np.abs(got - ref).max() <= 1e-6 * np.abs(ref).max()
    # an unrefined single-precision solve is far less accurate: the refinement matters
    raw = fac.data._solve32(rhs)
    assert np.abs(raw - ref).max() > 100 * np.abs(got - ref).max()
    # several right-hand sides at once
    R = np.column_stack([rhs, np.arange(rhs.size, dtype=float)])
    np.testing.assert_allclose(
        fac.solve(R), np.linalg.solve(_dense(st, blocks), R), rtol=0, atol=1e-6 * np.abs(R).max()
    )


def test_a_matrix_too_ill_conditioned_for_single_precision_is_solved_in_double(always_single):
    st, blocks, rhs = _reduced_system()
    D = _dense(st, blocks)
    # the angles of image 0 nearly free: S − α·u uᵀ with α just below 1/(uᵀ S⁻¹ u), u on
    # image 0's angles (scaled to S's diagonal): the condition after scaling to a unit
    # diagonal (what single precision feels, not the units) ≈ 1e9 ≫ 1/u₃₂
    u = np.zeros(6)
    u[3:] = np.sqrt(np.diag(D)[3:6])
    alpha = 1.0 / (
        np.pad(u, (0, D.shape[0] - 6)) @ np.linalg.solve(D, np.pad(u, (0, D.shape[0] - 6)))
    )
    bad = blocks.copy()
    bad[st.diag_block[0]] -= (1 - 1e-4) * alpha * np.outer(u, u)
    fac = factor_reduced(st, bad.copy(), single=True)
    got = fac.solve(rhs)
    if fac.kind == "mixed":  # spbtrf got through: the refinement must have given up
        assert fac.data.fallback is not None and fac.data.rounds[-1] == -1
    else:  # spbtrf broke down: factored in double precision at once
        assert fac.kind == "banded"
    ref = np.linalg.solve(_dense(st, bad), rhs)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-6 * np.abs(ref).max())


def test_a_refinement_that_does_not_contract_falls_back_to_double_precision(always_single):
    st, blocks, rhs = _reduced_system()
    good = factor_reduced(st, blocks.copy(), single=True)
    # a single-precision factor of 0.3·S: each round multiplies the error by I − S/0.3S
    wrong = factor_reduced(st, 0.3 * blocks, single=True).data
    double = factor_reduced(st, blocks.copy())
    fac = mixed.MixedBandFactor(wrong.c32, good.data.S, good.data.perm, lambda: double)
    calls = []
    solve32 = fac._solve32
    fac._solve32 = lambda r: calls.append(1) or solve32(r)
    got = fac.solve(rhs)
    # given up after the first round (its correction is not small), not after MAX_ROUNDS
    assert fac.fallback is double and fac.rounds == [-1] and len(calls) == 2
    np.testing.assert_array_equal(got, double.solve(rhs))


def test_the_bundle_reaches_the_same_optimum_with_single_precision_factors(monkeypatch):
    sim = ov.simulate_block(4, 10, rng=21)
    kinds = []
    original = reduced.factor_reduced

    def spy(*args, **kw):
        fac = original(*args, **kw)
        kinds.append(fac.kind)
        return fac

    import orientviz.bundle._problem as problem

    monkeypatch.setattr(problem, "factor_reduced", spy)
    monkeypatch.setattr(reduced, "MIN_BAND_FLOPS", np.inf)
    double = ov.bundle_adjust(sim.block, precision=False, solver="banded")
    assert set(kinds) == {"banded"}
    kinds.clear()
    monkeypatch.setattr(reduced, "MIN_BAND_FLOPS", 0.0)
    single = ov.bundle_adjust(sim.block, precision=False, solver="banded")
    assert set(kinds) == {"mixed"}
    assert single.iterations == double.iterations
    assert abs(single.sigma0 - double.sigma0) < 1e-12 * double.sigma0
    scale = np.abs(double.x).max()
    np.testing.assert_allclose(single.x, double.x, rtol=0, atol=1e-10 * scale)
    # with the precision pass the factors stay in double precision
    kinds.clear()
    ov.bundle_adjust(sim.block, precision=True, solver="banded")
    assert "mixed" not in kinds
