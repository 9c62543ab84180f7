"""The fast bundle against the textbook reference (orientviz.bundle.reference).

The reference linearises, forms N11, N12, N22, reduces densely and back-substitutes; it
shares with the fast bundle only the conventions' functions (rotation matrices, the
datum rules of ``point_setup``) and the camera model. Both are iterated far below the
default tolerance and must reach the same optimum to 1e-10 relative: projection centres
and points relative to the median ray length L, angles in rad (a rotation error Δθ
moves a point at distance L by L·Δθ, so Δθ is the same relative measure), additional
parameters relative to their largest value, σ̂0 relative.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

import orientviz as ov
from orientviz.bundle.loop import _steps
from orientviz.bundle.reference import (
    collinearity,
    linearise,
    normal_equations,
    reference_bundle,
    reference_data,
    solve_step,
)
from orientviz.bundle.sparsity import bundle_normal_blocks
from orientviz.rotation import convert_sequence, matrix_derivatives, matrix_from_opk

TOL = 1e-9  # both iterate far below the default 5e-3 (conditional σ units)
AGREE = 1e-10  # the relative agreement asked of every fast path


def relative_difference(res, ref, block) -> dict[str, float]:
    """Largest relative differences between a BundleResult and a ReferenceSolution."""
    unknown = ~np.isin(np.arange(block.n_points), np.flatnonzero(block.points.role == 2))
    obs = block.observations
    L = float(np.median(np.linalg.norm(ref.xyz[obs.point] - ref.X0[obs.image], axis=1)))
    scale_ap = max(1.0, float(np.max(np.abs(ref.ap), initial=0.0)))
    s0_ref = np.sqrt(ref.cost[-1] / res.redundancy)
    return {
        "X0": float(np.max(np.abs(res.exterior[:, :3] - ref.X0))) / L,
        "angles": float(np.max(np.abs(res.exterior[:, 3:] - ref.angles))),
        "points": float(np.max(np.abs(res.points[unknown] - ref.xyz[unknown]))) / L,
        "additional": float(np.max(np.abs(res.additional - ref.ap), initial=0.0)) / scale_ap,
        "sigma0": abs(res.sigma0 / s0_ref - 1.0),
    }


def textbook_cofactors(data, ref, sequence: str):
    """Q11 = S⁻¹ (x1) and the point blocks Q22_j = N22_j⁻¹ + T_jᵀ Q11 T_j,
    T_j = N12_j N22_j⁻¹, from the reference's normal equations at its optimum."""
    f, A1, B = linearise(data, ref.X0, ref.angles, ref.xyz, ref.ap, sequence)
    N11, N12, N22, *_ = normal_equations(data, f, A1, B, ref.X0, ref.angles, ref.xyz, ref.ap)
    N22inv = np.linalg.inv(N22)
    T = np.einsum("pia,pab->pib", N12, N22inv)
    Q11 = np.linalg.inv(N11 - np.einsum("pia,pja->ij", T, N12))
    return Q11, N22inv + np.einsum("pia,ij,pjb->pab", T, Q11, T)


def assert_same_optimum(res, ref, block, agree=AGREE):
    assert res.converged and ref.converged, (res.reason, ref.reason)
    d = relative_difference(res, ref, block)
    assert max(d.values()) < agree, d


@pytest.fixture(autouse=True, scope="module")
def one_blas_thread():
    """Matrices of a few hundred rows: BLAS threads only wait for each other (5× the time
    on a loaded 2-core machine); the results do not depend on it."""
    with threadpool_limits(limits=1, user_api="blas"):
        yield


@pytest.fixture(scope="module")
def strips():
    """3 strips × 6 images, perimeter XYZ control held fixed (the library's default)."""
    return ov.simulate_block(3, 6, rng=11, extra=None).block


@pytest.fixture(scope="module")
def strips_reference(strips):
    return reference_bundle(strips, tol=TOL, max_iter=50)


def test_partial_derivatives_equal_central_differences():
    rng = np.random.default_rng(5)
    n = 9
    X = rng.normal(0, 200, (n, 3))
    X0 = rng.normal(0, 20, (n, 3)) + [0, 0, 1500]
    ang = rng.uniform(-0.4, 0.4, (n, 3))
    c = np.full(n, 152.0)

    def xy(X, X0, ang):
        R = matrix_from_opk(ang[:, 0], ang[:, 1], ang[:, 2], "opk")
        dR = np.stack(matrix_derivatives(ang[:, 0], ang[:, 1], ang[:, 2], "opk"))
        return collinearity(X, X0, R, dR, c)

    f, dX0, dang, dX = xy(X, X0, ang)
    # the value is the package's collinearity (camera.project, principal point 0)
    R = matrix_from_opk(ang[:, 0], ang[:, 1], ang[:, 2], "opk")
    assert np.allclose(f, ov.camera.project(X, X0, R, c), rtol=0, atol=1e-12)
    for what, arr, J, h in (("X0", X0, dX0, 1e-3), ("angles", ang, dang, 1e-7), ("X", X, dX, 1e-3)):
        for k in range(3):
            plus, minus = arr.copy(), arr.copy()
            plus[:, k] += h
            minus[:, k] -= h
            args = {"X0": (X, plus, ang), "angles": (X, X0, plus), "X": (plus, X0, ang)}[what]
            args_m = {"X0": (X, minus, ang), "angles": (X, X0, minus), "X": (minus, X0, ang)}[what]
            num = (xy(*args)[0] - xy(*args_m)[0]) / (2 * h)
            np.testing.assert_allclose(J[:, :, k], num, rtol=1e-6, atol=1e-9 * np.abs(J).max())


def test_one_reduced_step_is_the_whole_system_solved_densely(strips):
    su = reference_data(strips)
    X0, ang, xyz = strips.images.X0, strips.images.angles, su.xyz0
    ap = su.ap0
    f, A1, B = linearise(su, X0, ang, xyz, ap, strips.sequence)
    N11, N12, N22, n1, n2, _ = normal_equations(su, f, A1, B, X0, ang, xyz, ap)
    dx1, dx2 = solve_step(N11, N12, N22, n1, n2)
    u1, p = N11.shape[0], N22.shape[0]
    N = np.zeros((u1 + 3 * p,) * 2)
    N[:u1, :u1] = N11
    for j in range(p):
        s = slice(u1 + 3 * j, u1 + 3 * j + 3)
        N[:u1, s] = N12[j]
        N[s, :u1] = N12[j].T
        N[s, s] = N22[j]
    n = np.concatenate([n1, n2.ravel()])
    got = np.concatenate([dx1, dx2.ravel()])
    # N mixes m and rad: equilibrated, its condition is still ~1e6 (the block's weak
    # bending modes), so two solves may differ by ~1e6·eps relative; the residual of the
    # reduced solution (backward error, equilibrated) must be at rounding level
    d = 1 / np.sqrt(np.diag(N))
    want = d * np.linalg.solve(d[:, None] * N * d, d * n)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-8 * np.abs(want).max())
    assert np.abs(d * (N @ got - n)).max() < 1e-11 * np.abs(d * n).max()


def _step_kinds(monkeypatch) -> dict[str, int]:
    """Count the fast bundle's steps by kind: chord steps (solved with an older factor of
    S) and steps in rotations of the image frames (taken while the start is poor)."""
    count = {"chord": 0, "frame": 0, "all": 0}
    solve = _steps.BundleSteps.solve

    def spy(self, st, ev, lam, it):
        out = solve(self, st, ev, lam, it)
        count["chord"] += int(self.chord_step)
        count["frame"] += int(self.is_local(ev))
        count["all"] += 1
        return out

    monkeypatch.setattr(_steps.BundleSteps, "solve", spy)
    return count


@pytest.mark.parametrize("solver", ["dense", "banded", "sparse"])
@pytest.mark.parametrize("precision", [True, False], ids=["newton", "chord"])
def test_every_reduced_solver_reaches_the_reference_optimum(
    solver, precision, strips, strips_reference, monkeypatch
):
    steps = _step_kinds(monkeypatch)
    res = ov.bundle_adjust(strips, solver=solver, tol=TOL, max_iter=50, precision=precision)
    assert res.solver == solver
    # without the precision the fast bundle takes chord steps (an older factor of S, in
    # single precision with refinement); with it every step is a full Newton step; from
    # this poor start (σ0 ≈ 1250) the first steps rotate the image frames
    assert (steps["chord"] > 0) == (not precision), steps
    assert steps["frame"] > 0, steps
    assert_same_optimum(res, strips_reference, strips)


@pytest.mark.parametrize("solver", ["auto", "banded", "sparse"])
def test_a_larger_block_and_real_nested_dissection(solver):
    # 4 × 12 images: the sparse solver's nested dissection splits S into several fronts
    block = ov.simulate_block(4, 12, rng=3, extra=None).block
    ref = _cached_reference(block, "4x12")
    res = ov.bundle_adjust(block, solver=solver, tol=TOL, max_iter=50, precision=False)
    if solver == "sparse":
        assert res.reduced_info["fronts"] > 2, res.reduced_info
    assert_same_optimum(res, ref, block)


_REFERENCES: dict[str, object] = {}


def _cached_reference(block, key: str):
    if key not in _REFERENCES:
        _REFERENCES[key] = reference_bundle(block, tol=TOL, max_iter=50)
    return _REFERENCES[key]


def test_the_phi_omega_kappa_sequence():
    sim = ov.simulate_block(2, 6, rng=4, extra=None)
    block = copy.deepcopy(sim.block)
    a = block.images.angles
    block.images.angles = np.column_stack(convert_sequence(a[:, 0], a[:, 1], a[:, 2], "opk", "pok"))
    block.sequence = "pok"
    ref = reference_bundle(block, tol=TOL, max_iter=50)
    res = ov.bundle_adjust(block, tol=TOL, max_iter=50)
    assert_same_optimum(res, ref, block)
    # the same block in ω-φ-κ: the same optimum, the angles of another sequence
    opk = reference_bundle(sim.block, tol=TOL, max_iter=50)
    assert np.max(np.abs(opk.xyz - ref.xyz)) < 1e-8
    back = np.column_stack(convert_sequence(*ref.angles.T, "pok", "opk"))
    d = (back - opk.angles + np.pi) % (2 * np.pi) - np.pi  # κ near ±π may wrap
    assert np.max(np.abs(d)) < 1e-11


def test_solver_reference_returns_the_same_typed_result(strips, strips_reference):
    fast = ov.bundle_adjust(strips, tol=TOL, max_iter=50)
    res = ov.bundle_adjust(strips, solver="reference", tol=TOL, max_iter=50)
    assert type(res) is type(fast) and res.solver == "reference"
    assert res.converged and res.reason == strips_reference.reason
    assert len(res.history) == len(strips_reference.cost)
    assert res.history[-1].cost == pytest.approx(strips_reference.cost[-1], rel=1e-14)
    assert res.sigma0 == pytest.approx(fast.sigma0, rel=AGREE)
    assert (res.redundancy, res.adjusted) == (fast.redundancy, fast.adjusted)
    assert res.residuals.shape == fast.residuals.shape
    scale = np.abs(fast.residuals).max()
    assert np.max(np.abs(res.residuals - fast.residuals)) < 1e-9 * scale
    np.testing.assert_allclose(res.redundancy_numbers, fast.redundancy_numbers, atol=1e-8)
    np.testing.assert_allclose(res.std(), fast.std(), rtol=1e-8)
    assert_same_optimum(res, strips_reference, strips)


def test_the_precision_equals_the_inverse_of_the_reference_normal_equations(
    strips, strips_reference
):
    # Q11 = S⁻¹ of the orientations and, per point, Q22_j = N22_j⁻¹ + T_jᵀ Q11 T_j with
    # T_j = N12_j N22_j⁻¹: the textbook cofactors at the optimum, against the fast
    # precision code (banded selected inverse)
    ref = strips_reference
    su = reference_data(strips)
    Q11, Q22 = textbook_cofactors(su, ref, strips.sequence)
    fast = ov.bundle_adjust(strips, solver="banded", tol=TOL, max_iter=50)
    s0 = np.sqrt(ref.cost[-1] / fast.redundancy)
    want_ext = s0 * np.sqrt(np.diag(Q11))
    want_pts = s0 * np.sqrt(np.einsum("pii->pi", Q22))
    std = fast.std()
    got_pts = std[fast.groups["points"]].reshape(-1, 3)[su.unknown]
    np.testing.assert_allclose(std[fast.groups["exterior"]], want_ext, rtol=1e-8)
    np.testing.assert_allclose(got_pts, want_pts, rtol=1e-8)


def test_weighted_and_partial_control_and_observed_centres():
    # heights-only chains (xy+z), weighted noisy control, two check points, and GNSS-like
    # observed projection centres: every pseudo-observation of the normal equations
    sim = ov.simulate_block(3, 5, rng=5, extra=None, control="chains", control_kind="xy+z",
                            control_sigma=0.05, control_noise=0.05, n_check=2)  # fmt: skip
    block = copy.deepcopy(sim.block)
    rng = np.random.default_rng(7)
    block.images.X0_obs = sim.truth.images.X0 + rng.normal(0, 0.1, (block.n_images, 3))
    block.images.X0_sigma = np.full((block.n_images, 3), 0.1)
    # coordinates held by σ = 1 µm (FIXED_SIGMA_M) leave a noise floor of the stopping
    # measure near 1e-8 conditional σ: both stop at 1e-7 (the optimum is then met to ~1e-13)
    for control in ("weighted", "fixed"):
        ref = reference_bundle(block, control=control, tol=1e-7, max_iter=50)
        for solver in ("dense", "banded"):
            res = ov.bundle_adjust(block, control=control, solver=solver, tol=1e-7, max_iter=50)
            assert_same_optimum(res, ref, block)


def test_lesson_10s_normal_blocks_are_the_reference_blocks(strips):
    # bundle/sparsity.py (lesson 10's U, W, V, bc, bp) against the reference's N11, N12,
    # N22, n1, n2 at the approximations: the lesson's building blocks are the textbook's
    nb = bundle_normal_blocks(strips)
    data = reference_data(strips)
    X0, ang, xyz, ap = strips.images.X0, strips.images.angles, data.xyz0, data.ap0
    f, A1, B = linearise(data, X0, ang, xyz, ap, strips.sequence)
    N11, N12, N22, n1, n2, vtpv = normal_equations(data, f, A1, B, X0, ang, xyz, ap)
    m, q = nb.n_images, nb.n_points
    assert q == data.unknown.size and np.array_equal(
        np.flatnonzero(nb.unknown_point >= 0), data.unknown
    )
    U = np.zeros((6 * m, 6 * m))
    for i in range(m):
        U[6 * i : 6 * i + 6, 6 * i : 6 * i + 6] = nb.U[i]
    W = N12.transpose(1, 0, 2).reshape(6 * m, 3 * q)
    for got, want in ((N11, U), (W, nb.W), (N22, nb.V), (n1, nb.bc), (n2.ravel(), nb.bp)):
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-10 * np.abs(want).max())
    assert vtpv == pytest.approx(nb.vtpv, rel=1e-12)


def test_the_options_route_to_the_reference(strips, strips_reference):
    res = ov.bundle_adjust(
        strips, options=ov.bundle.BundleOptions(solver="reference", tol=TOL, max_iter=50),
        precision=False,
    )  # fmt: skip
    assert res.solver == "reference" and res.reason == strips_reference.reason
    assert np.array_equal(res.exterior[:, :3], strips_reference.X0)
    with pytest.raises(ov.InputError, match="auxiliary"):
        ov.bundle_adjust(strips, solver="reference", auxiliary=[object()])
