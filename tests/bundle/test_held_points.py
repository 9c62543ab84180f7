"""Points whose block V is numerically singular are held along their weak directions in a
step (:func:`orientviz.bundle.reduced.inv3_held`), not inverted into NaN.

A point whose rays have become parallel — receding to infinity, as points seen only by
rays a Cauchy loss has down-weighted do on Ladybug — has a block V whose smallest
eigenvalue is below the rounding of the others: its adjugate inverse is noise, inf or NaN,
and T = W V⁻¹ carried it into S ("invalid value encountered in matmul", a NaN step).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import orientviz as ov
from orientviz.bundle import BundleOptions, bundle_adjust
from orientviz.bundle.loop._depth import DEPTH_FAR_SIZES
from orientviz.bundle.reduced import SINGULAR_REL_EIG, inv3, inv3_held
from orientviz.camera import project
from orientviz.plausibility import check_block
from orientviz.rotation import matrix_from_opk


def _blocks(rng, n):
    """n random well-conditioned symmetric positive definite 3 × 3 blocks."""
    J = rng.normal(size=(n, 6, 3))
    return J.transpose(0, 2, 1) @ J


def test_regular_blocks_keep_the_adjugate_inverse():
    """Blocks without a weak eigenvalue: :func:`inv3`'s values bit for bit, nothing held."""
    V = _blocks(np.random.default_rng(1), 500)
    out, held = inv3_held(V)
    assert held is None
    assert np.array_equal(out, inv3(V))


@pytest.mark.parametrize("weak", [0.0, 1e-17, 0.5 * SINGULAR_REL_EIG])
def test_a_weak_direction_is_left_out_of_the_inverse(weak):
    """V = λ₁aaᵀ + λ₂bbᵀ + weak·λ₁nnᵀ (orthonormal a, b, n), weak ≤ SINGULAR_REL_EIG: held;
    its inverse is the pseudo-inverse on a, b (V⁺n = 0, V V⁺ a = a), the regular blocks
    beside it keep their inverses."""
    rng = np.random.default_rng(2)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    a, b, n = Q.T
    lam1, lam2 = 4.0e-20, 1.5e-20  # a point at ~1e10 model units: tiny blocks
    Vw = lam1 * np.outer(a, a) + lam2 * np.outer(b, b) + weak * lam1 * np.outer(n, n)
    V = np.concatenate([_blocks(rng, 4), Vw[None], _blocks(rng, 3)])
    out, held = inv3_held(V)
    assert held is not None and held.points.tolist() == [4]
    P = out[4]
    assert np.all(np.isfinite(P))
    assert np.allclose(P, P.T, rtol=0, atol=1e-9 * np.abs(P).max())
    assert np.linalg.norm(P @ n) <= 1e-9 * np.linalg.norm(P)
    assert np.allclose(Vw @ P @ a, a, atol=1e-9)
    assert np.allclose(Vw @ P @ b, b, atol=1e-9)
    assert np.allclose(held.factors[0] @ held.factors[0].T, P, rtol=0, atol=1e-9 * np.abs(P).max())
    keep = np.r_[0:4, 5:8]
    assert np.array_equal(out[keep], inv3(V[keep]))


def _far_point_block(distance: float):
    """A small simulated block with one two-ray tie point moved ``distance`` times its
    distance from one of its images along that ray (its rays nearly parallel there)."""
    b = ov.simulate_block(2, 5, rng=3, start_error=None).block
    obs = b.observations
    counts = np.bincount(obs.point, minlength=b.n_points)
    j = int(np.flatnonzero((b.points.role == 0) & (counts == 2))[0])
    X0 = b.images.X0[obs.image[np.flatnonzero(obs.point == j)[0]]].copy()
    b.points.xyz[j] = X0 + distance * (b.points.xyz[j] - X0)
    return b, j, X0


@pytest.mark.parametrize("loss", ["none", "cauchy"])
def test_a_step_holds_a_point_whose_block_is_singular(loss):
    """A point at 1e9 times its distance along one of its rays (V's depth eigenvalue ~1e-18
    of the others): the step is finite, without NaN warnings, and moves that point across
    its ray only; the rest of the block moves as a step does (finite, the cost lower;
    the robust run: its least-squares steps, max_iter times ROBUST_ITER_FACTOR).
    Before: V⁻¹ non-finite, "invalid value encountered in matmul", and least squares ended
    in an internal error (a NaN rotation)."""
    block, j, X0 = _far_point_block(1e9)
    start = block.points.xyz[j].copy()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = bundle_adjust(
            block,
            options=BundleOptions(loss=loss, damping="fallback", max_iter=1, history_x=True),
            precision=False,
        )
    assert len(res.history) >= 2 and all(h.damping == 0.0 for h in res.history)
    assert all(b.cost < a.cost for a, b in zip(res.history, res.history[1:]))
    assert np.all(np.isfinite(res.exterior)) and np.all(np.isfinite(res.points))
    u = (start - X0) / np.linalg.norm(start - X0)
    m = block.n_images
    first = res.history[1].x[6 * m : 6 * m + 3 * block.n_points].reshape(-1, 3)
    move = first[j] - start  # in the first step
    assert abs(move @ u) <= 1e-6 * max(np.linalg.norm(move), 1e-3)


@pytest.mark.parametrize("loss", ["none", "huber"])
def test_a_held_point_reaches_the_optimum_of_its_rays(loss):
    """The point moved 1e9 times its distance along one of its rays: a tight run brings it
    back to where its rays meet and ends at the optimum of the block solved from the
    unmoved point (the depth of a held point is sought alone after each step,
    :mod:`orientviz.bundle.loop._depth`). Before: the held depth never moved; the run
    ended with the point at ~1e12 and vᵀPv 1.5e5 times the optimum (Huber: Σρ 135 times)."""
    opts = BundleOptions(loss=loss, ftol=1e-14, tol=1e-12, max_iter=200)
    block, j, X0 = _far_point_block(1.0)
    ref = bundle_adjust(block, options=opts, precision=False)
    far, _, _ = _far_point_block(1e9)
    res = bundle_adjust(far, options=opts, precision=False)
    assert res.converged
    c, c_ref = res.history[-1].cost, ref.history[-1].cost
    assert abs(c - c_ref) <= 1e-10 * c_ref
    assert np.linalg.norm(res.points[j] - ref.points[j]) <= 1e-6 * np.linalg.norm(
        ref.points[j] - X0
    )


def _point_at_infinity_block():
    """The small simulated block with one two-ray tie point whose second ray is made
    parallel to its first (its observation in the second image: the direction from the
    first image's centre to the point), so that the point's rays meet only at infinity;
    the point starts 1e3 times its distance from the first image along that ray."""
    block, j, X0 = _far_point_block(1e3)
    obs, im = block.observations, block.images
    rows = np.flatnonzero(obs.point == j)
    a, b = obs.image[rows]
    R = matrix_from_opk(im.angles[b, 0], im.angles[b, 1], im.angles[b, 2], block.sequence)
    cam = im.camera[b]
    d = block.points.xyz[j] - im.X0[a]
    obs.xy[rows[1]] = project(im.X0[b] + d, im.X0[b], R, block.cameras.c[cam],
                              block.cameras.x0[cam], block.cameras.y0[cam])  # fmt: skip
    return block, j


@pytest.mark.parametrize("loss", ["none", "cauchy"])
def test_a_point_at_infinity_stays_a_readable_coordinate(loss):
    """A point whose rays meet only at infinity recedes while the run is held, but no
    farther than DEPTH_FAR_SIZES block sizes from its images: the result's coordinates
    pass the plausibility check as a written file would (a warning, no error). Before: the
    depth search took it 1000-fold out per step, to 1e17 and beyond (a written result was
    refused when read again: "far outside", "a coordinate beyond ±1e+15")."""
    block, j = _point_at_infinity_block()
    opts = BundleOptions(loss=loss, ftol=1e-14, tol=1e-12, max_iter=60)
    res = bundle_adjust(block, options=opts, precision=False)
    size = float(np.max(np.ptp(block.images.X0, axis=0)))  # (the cameras move little)
    centre = block.images.X0[block.observations.image[block.observations.point == j]].mean(axis=0)
    dist = float(np.linalg.norm(res.points[j] - centre))
    assert dist > 1e6 * size  # it did recede (held, its depth sought)
    assert dist <= 1.01 * DEPTH_FAR_SIZES * size
    solved = block.copy()
    solved.points.xyz[:] = res.points
    errors = [f for f in check_block(solved) if f.level == "error"]
    assert not errors, errors


def test_the_iteration_limit_help_names_the_robust_factor():
    """``orientviz solve --max-iter``'s help says how many steps a robust run may take
    (ROBUST_ITER_FACTOR times the limit)."""
    from orientviz.bundle.loop._adjust import ROBUST_ITER_FACTOR
    from orientviz.cli import COMMANDS

    (arg,) = [a for a in COMMANDS["solve"].arguments if "--max-iter" in a.names]
    assert f"{ROBUST_ITER_FACTOR} times as many" in arg.options["help"]
