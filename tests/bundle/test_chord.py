"""Chord steps of the bundle (``BundleOptions.chord_reuse``): the factor of a small step serves the next.

A chord step solves with the normal matrix of an earlier iterate: it is right only as far
as that matrix is close to the current one, and the stopping rule reads its correction as
a Newton step's. These tests pin what makes that sound: the change between rotations of
the image frames and ω, φ, κ, the solution (the all-Newton one), the fall-back to a full
step when chord steps stop contracting, and that the steps judged by the stopping rule
are in ω, φ, κ.
"""

from __future__ import annotations

import numpy as np
import pytest
from unordered_networks import close_range_network

import orientviz as ov
from orientviz.bundle import BundleOptions
from orientviz.bundle.loop import _steps
from orientviz.bundle.model import angle_map, apply_local, collinearity_block
from orientviz.bundle.problem import BundleProblem, BundleState, point_setup


@pytest.mark.parametrize("sequence", ["opk", "pok"])
def test_angle_map_turns_frame_rotation_derivatives_into_angle_derivatives(sequence):
    rng = np.random.default_rng(2)
    m, n = 5, 40
    angles = rng.uniform(-1.2, 1.2, (m, 3))
    X0 = rng.normal(0, 5, (m, 3)) + [0, 0, 100]
    c, z = np.full(m, 50.0), np.zeros(m)
    image, xyz = rng.integers(0, m, n), rng.normal(0, 20, (n, 3))
    A = angle_map(angles, sequence)
    _, J_angles, _ = collinearity_block(X0, angles, c, z, z, image, xyz, sequence)
    _, J_frame, _ = collinearity_block(X0, angles, c, z, z, image, xyz, sequence, local=True)
    scale = np.abs(J_angles[:, :, 3:]).max()
    np.testing.assert_allclose(
        J_frame[:, :, 3:] @ A[image], J_angles[:, :, 3:], rtol=0, atol=1e-12 * scale
    )
    # a small change of the angles is the frame rotation A·dθ (to first order)
    d = rng.normal(0, 1e-6, (m, 3))
    turned = apply_local(angles, (A @ d[:, :, None])[:, :, 0], sequence)
    np.testing.assert_allclose(turned, angles + d, rtol=0, atol=1e-10)


def test_a_frame_rotation_factor_gives_the_angle_newton_step_at_its_own_iterate():
    # at the iterate of the factor itself N_θ = Tᵀ N_δ T holds exactly: the chord step
    # in ω, φ, κ by the factor of the step in frame rotations is the Newton step there
    block, _ = close_range_network(m=12, p=120, start_error=0.1)
    prob = BundleProblem(block, point_setup(block, "fixed"))
    names = prob.names()[: 6 * prob.m]
    xyz = block.points.xyz.copy()
    st = BundleState(block.images.X0, block.images.angles, xyz, np.zeros(0), np.zeros(0))
    rw, Je, Jp = prob.residuals(st, jac=True)
    newton = prob.normal(st, rw, Je, Jp)
    dc, dp, _, _ = prob.solve(newton, names)
    local = prob.normal(st, *prob.residuals(st, jac=True, local=True))
    _, _, _, fac = prob.solve(local, names)
    A = angle_map(st.angles, block.sequence)
    chord = prob.chord_normal(st, rw, Je, Jp, local, rot=A)
    dc_c, dp_c, _, _ = prob.solve(chord, names, fac=fac)
    dc_c[:, 3:] = np.linalg.solve(A, dc_c[:, 3:, None])[:, :, 0]
    np.testing.assert_allclose(dc_c, dc, rtol=1e-7, atol=1e-9 * np.abs(dc).max())
    np.testing.assert_allclose(dp_c, dp, rtol=1e-7, atol=1e-9 * np.abs(dp).max())
    # the stopping rule's diagonal is the one of ω, φ, κ
    np.testing.assert_allclose(chord.diagU, newton.diagU, rtol=1e-12)
    assert not np.allclose(local.diagU[:, 3:], newton.diagU[:, 3:], rtol=1e-3)


def _record(monkeypatch):
    """Per solved step: (chord step?, correction, local?, chord by a frame-rotation
    factor in ω, φ, κ?, iteration) and per tried chord whether it was refused."""
    steps, refused = [], []
    solve, chord = _steps.BundleSteps.solve, _steps.BundleSteps._chord

    def spy_solve(self, st, ev, lam, it):
        out = solve(self, st, ev, lam, it)
        converted = self.chord_step and self.chord_factor[2] and not self.last_local
        steps.append((self.chord_step, out.max_correction, self.last_local, converted, it))
        return out

    def spy_chord(self, *args):
        out = chord(self, *args)
        refused.append(out is None)
        return out

    monkeypatch.setattr(_steps.BundleSteps, "solve", spy_solve)
    monkeypatch.setattr(_steps.BundleSteps, "_chord", spy_chord)
    return steps, refused


def _assert_same_optimum(res, ref, sd):
    """Both within 1 % of the a-priori σ of every estimated parameter (each run stops
    within tol = 0.005 of its conditional σ, which is smaller than the σ)."""
    assert res.converged and ref.converged
    est = np.isfinite(sd) & (sd > 0)
    d = (res.x - ref.x)[est]
    n_ext = 6 * res.exterior.shape[0]
    d[:n_ext].reshape(-1, 6)[:, 3:] = (d[:n_ext].reshape(-1, 6)[:, 3:] + np.pi) % (
        2 * np.pi
    ) - np.pi
    assert np.max(np.abs(d) / sd[est]) < 1e-2
    assert res.sigma0 == pytest.approx(ref.sigma0, rel=1e-9)


@pytest.fixture
def poor_start():
    """Start 0.3 m / 0.03 rad off: two steps in rotations of the image frames, the third
    (still local) moves 5e-4 of the ray length: its factor serves the steps in ω, φ, κ."""
    block, _ = close_range_network(m=12, p=120, start_error=0.3)
    sd = ov.bundle_adjust(block, precision=True).std(a_posteriori=False)
    return block, sd


def test_chord_steps_after_a_frame_rotation_step_reach_the_newton_optimum(monkeypatch, poor_start):
    block, sd = poor_start
    steps, _ = _record(monkeypatch)
    res = ov.bundle_adjust(block, precision=False)
    chords = list(steps)
    steps.clear()
    newton_steps = BundleOptions(chord_reuse=0.0)  # every step a Newton step
    newton = ov.bundle_adjust(block, precision=False, options=newton_steps)
    full_newton = len(steps)
    _assert_same_optimum(res, newton, sd)
    assert any(s[3] for s in chords)  # a local step's factor served a step in ω, φ, κ
    assert chords[-1][0] and not chords[-1][2]  # the rule stopped on a chord in ω, φ, κ
    assert sum(not s[0] for s in chords) < full_newton  # fewer factors of S


def test_chord_steps_that_stop_contracting_fall_back_to_full_steps(monkeypatch, poor_start):
    block, sd = poor_start
    # every undamped step's factor is offered to the next: after the long first steps
    # the old matrix no longer contracts, and the step is solved in full instead
    always = BundleOptions(chord_reuse=np.inf)
    steps, refused = _record(monkeypatch)
    res = ov.bundle_adjust(block, precision=False, options=always)
    taken, refusals = list(steps), list(refused)
    newton = ov.bundle_adjust(block, precision=False, options=BundleOptions(chord_reuse=0.0))
    _assert_same_optimum(res, newton, sd)
    assert any(refusals) and not all(refusals)
    for before, step in zip(taken, taken[1:]):
        if step[0]:  # each chord step shrank the correction by the contraction bound
            assert step[1] < always.chord_contraction * before[1]


def test_steps_after_a_small_correction_are_in_the_angles_even_if_sigma0_stays_large(
    monkeypatch,
):
    # the observations' σ 50 times too small: σ0 ≈ 50 at the optimum, which alone would
    # keep the steps in rotations of the image frames
    block, _ = close_range_network(m=12, p=120, start_error=0.3)
    block.observations.sigma[:] *= 0.02
    steps, _ = _record(monkeypatch)
    res = ov.bundle_adjust(block, precision=False)
    assert res.converged and res.sigma0 > 30
    assert len({s[4] for s in steps}) == len(steps)  # no step was retried damped
    for (_, corr, _, _, _), (_, _, local_next, _, _) in zip(steps, steps[1:]):
        if corr < BundleOptions().local_min_correction:
            assert not local_next
    assert steps[0][2] and not steps[-1][2]
