"""Checkers for lesson 10 (sparse normal equations: Schur complement, back-substitution, bandwidth).

Oracles: the whole normal system solved densely (numpy) for the reduction, the
back-substitution and the covariance of a point; the library's pattern of simulated blocks for
the predicted bandwidth and the fill-in.
"""

from __future__ import annotations

import numpy as np

from ..bundle import bundle_adjust
from ..bundle.reduced import geometric_orderings
from ..bundle.reference import (
    collinearity,
    linearise,
    normal_equations,
    reference_bundle,
    reference_data,
)
from ..bundle.sparsity import (
    BundleNormal,
    bandwidth,
    bundle_normal_blocks,
    cholesky_fill,
    reduced_pattern,
)
from ..rotation import matrix_derivatives, matrix_from_opk
from ..simulate import simulate_block
from ._common import (
    INVERTERS,
    CheckFailed,
    NotWrittenError,
    call,
    compare,
    complex_step,
    exact_derivatives,
    own_work,
    rng_for,
    small_matrices,
    success,
)
from .lesson02 import _rodrigues_opk
from .sliders import answer_value


def _system(rng, m=4, q=7):
    """A random normal system with bundle structure: m image blocks (6), q point blocks (3)."""
    sees = rng.random((m, q)) < 0.6
    sees[rng.integers(0, m, q), np.arange(q)] = True
    sees[np.arange(m), rng.integers(0, q, m)] = True
    U = np.zeros((6 * m, 6 * m))
    V = np.zeros((3 * q, 3 * q))
    W = np.zeros((6 * m, 3 * q))
    for i in range(m):
        for j in range(q):
            if sees[i, j]:
                J = rng.normal(size=(2, 9))
                A, B = J[:, :6], J[:, 6:]
                U[6 * i : 6 * i + 6, 6 * i : 6 * i + 6] += A.T @ A
                V[3 * j : 3 * j + 3, 3 * j : 3 * j + 3] += B.T @ B
                W[6 * i : 6 * i + 6, 3 * j : 3 * j + 3] += A.T @ B
    U += np.eye(6 * m) * 2.0  # control and other images: U regular
    V += np.eye(3 * q) * 0.5
    bc, bp = rng.normal(size=6 * m), rng.normal(size=3 * q)
    return U, W, V, bc, bp


def _reduce_wrong(U, W, V, bc, bp, mode):
    """The reduced system with one plausible mistake (mode "plus" or "no_inverse")."""
    if mode == "plus":
        Vi = np.linalg.inv(V)
        return U + W @ Vi @ W.T, bc + W @ Vi @ bp
    return U - W @ V @ W.T, bc - W @ V @ bp  # mode "no_inverse"


def _block_patterns(strips: int, per_strip: int) -> tuple[int, int, np.ndarray, np.ndarray]:
    """Half-bandwidths (images) of a simulated block's reduced pattern S in flight order and
    numbered across the strips (the better of the library's two geometric orderings), S and
    that ordering."""
    blk = simulate_block(strips, per_strip, rng=12, extra=None).block
    fixed = np.all(np.nan_to_num(blk.points.sigma, nan=1.0) == 0.0, axis=1)
    col = np.full(blk.n_points, -1)
    col[~fixed] = np.arange(int(np.sum(~fixed)))
    S = reduced_pattern(blk.observations.image, col[blk.observations.point], blk.n_images)
    best = min(geometric_orderings(blk.images.X0), key=lambda o: bandwidth(S, o))
    return bandwidth(S), bandwidth(S, best), S, best


@own_work(
    "a prediction is a law in s and n; building the block and counting its bandwidth (the "
    "stand-in measured_bandwidths above) is the measurement it is compared with",
    simulate_block=simulate_block,
    reduced_pattern=reduced_pattern,
    bandwidth=bandwidth,
    geometric_orderings=geometric_orderings,
)
def check_predicted_bandwidth(fn) -> None:
    """``fn(strips, per_strip) -> (along, across)``: the half-bandwidth of the reduced normal
    matrix S (in images) of a block flown strip by strip, back and forth, numbered in flight
    order (along) and column by column across the strips (across), predicted from the shape.

    Oracle: the library's pattern of S of simulated blocks of five shapes (two or more strips,
    more images per strip than twice the strips), bandwidth counted over all entries. The
    answer may not build a block or count a pattern's bandwidth (the library's
    ``simulate_block``, ``reduced_pattern``, ``bandwidth`` and ``geometric_orderings`` are
    watched).
    """
    cases = ((2, 6), (3, 9), (4, 11), (2, 15), (5, 13))
    for s, n in cases:
        along, across, _, _ = _block_patterns(s, n)
        got = call(fn, s, n, what="predicted_bandwidth")
        try:
            g_along, g_across = (float(v) for v in got)
        except (TypeError, ValueError):
            raise CheckFailed("predicted_bandwidth: return two numbers (along, across)") from None
        compare(f"bandwidth along the strips, {s} × {n}", g_along, float(along), rtol=0.0,
                scale=1.0, wrong=[
            ("n + 2: that is a strip flown in the same direction as the one before; here the "
             "strips are flown back and forth, so the first image of a strip meets the last of "
             "the next", float(n + 2)),
            ("2n + 1: in the neighbouring strip the image that starts a strip is coupled with "
             "the one at the same place, not two bases further", float(2 * n + 1)),
            ("(along, across) swapped?", float(across)),
        ])  # fmt: skip
        compare(f"bandwidth across the strips, {s} × {n}", g_across, float(across), rtol=0.0,
                scale=1.0, wrong=[
            ("2s: the neighbouring strip is reached too — two bases ahead and one strip over "
             "is 2s + 1 numbers away", float(2 * s)),
            ("s + 1: an image shares points with images two bases ahead, in its own strip and in "
             "the next", float(s + 1)),
            ("(along, across) swapped?", float(along)),
        ])  # fmt: skip
    success(f"your law gives the bandwidths of all {len(cases)} block shapes, both numberings")


def check_fill_in_start(answer: object, strips: int = 4, lo: int = 3, hi: int = 25) -> None:
    """The smallest number of images per strip (``lo``..``hi``) at which numbering across the
    strips gives a Cholesky factor of S with fewer non-zero blocks than numbering along them
    (``strips`` strips; the lesson's slider). Oracle: the library's fill-in, computed here."""
    got = answer_value(answer, "images per strip")
    if got is None:
        raise NotWrittenError(
            "images per strip: not written yet (type the value you read off the sliders)"
        )
    first_fill = first_band = None
    for n in range(lo, hi + 1):
        along, across, S, best = _block_patterns(strips, n)
        if first_band is None and across < along:
            first_band = n
        if int(cholesky_fill(S, best).sum()) < int(cholesky_fill(S, None).sum()):
            first_fill = n
            break
    if first_fill is None:  # pragma: no cover - the lesson's range always has one
        raise CheckFailed(f"no block of {strips} strips with {lo}..{hi} images saves fill-in")
    if got == first_fill:
        success(f"from {first_fill} images per strip on, numbering across saves fill-in "
                f"(the bandwidth drops from {first_band} on)")  # fmt: skip
        return
    if first_band is not None and got == first_band:
        why = (
            f"{first_band} is where the BANDWIDTH across becomes smaller; the fill-in "
            f"(non-zero blocks of L) is still the same there: L fills its envelope, not its band"
        )
    elif got == first_fill - 1:
        why = f"at {first_fill - 1} both numberings still fill the same number of blocks"
    else:
        why = "move the sliders again and compare the two lines' non-zero blocks of L"
    raise CheckFailed(f"images per strip: {got:g} — {why}", error=np.inf, tolerance=0.0)


# --------------------------------------------------------------------- one reduced step


def check_schur_step(fn) -> None:
    """``fn(nb) -> (dc, dp)``: one Gauss-Newton step of a bundle by reduction to the
    orientation unknowns (``nb`` from :func:`orientviz.bundle.sparsity.bundle_normal_blocks`)."""
    # 3 strips of 4 images with a grid of extra points: W is 72 × (3q), 3q > 72 (the whole V is
    # larger than S, so small_matrices tells them apart) and a transposed W cannot pass unnoticed
    seed = int(rng_for("lesson10.check_schur_step").integers(1000))
    sim = simulate_block(3, 4, rng=seed, extra="grid", extra_spacing_mm=60.0)
    nb = bundle_normal_blocks(sim.block)
    with (
        own_work(**{"nb.dense (the whole system solved densely)": BundleNormal.dense}),
        small_matrices(
            6 * nb.n_images,
            "the exercise eliminates the points block by block: only S (6m × 6m) and the 3 × 3 "
            "blocks of V are to be inverted or solved with, never the whole V or the whole N",
            **INVERTERS,
        ),
    ):
        got = call(fn, nb, what="schur_step")
    if not isinstance(got, tuple) or len(got) != 2:
        raise CheckFailed("schur_step: return the pair (dc, dp)")
    dc, dp = (np.asarray(g, dtype=float) for g in got)
    N, b = nb.dense()
    x = np.linalg.solve(N, b)  # oracle: the whole system, dense
    k = 6 * nb.n_images
    want_dc, want_dp = x[:k], x[k:]
    U = np.zeros((k, k))
    for i in range(nb.n_images):
        U[6 * i : 6 * i + 6, 6 * i : 6 * i + 6] = nb.U[i]
    Vfull = np.zeros((len(want_dp), len(want_dp)))
    for j in range(nb.n_points):
        Vfull[3 * j : 3 * j + 3, 3 * j : 3 * j + 3] = nb.V[j]
    wrong_plus = _reduce_wrong(U, nb.W, Vfull, nb.bc, nb.bp, "plus")
    compare("dc (orientation corrections)", dc, want_dc, rtol=1e-8, wrong=[
        ("S = U − W V⁻¹ Wᵀ and r = bc − W V⁻¹ bp: the sign is wrong", np.linalg.solve(*wrong_plus)),
        ("the right side is reduced too: r = bc − W V⁻¹ bp", np.linalg.solve(U - nb.W @ np.linalg.inv(Vfull) @ nb.W.T, nb.bc)),
    ])  # fmt: skip
    compare("dp (point corrections)", dp, want_dp, rtol=1e-8, wrong=[
        ("the coupling Wᵀ dc is missing: dp = V⁻¹ (bp − Wᵀ dc)", np.linalg.solve(Vfull, nb.bp)),
        ("the sign of Wᵀ dc is wrong: dp = V⁻¹ (bp − Wᵀ dc)", np.linalg.solve(Vfull, nb.bp + nb.W.T @ want_dc)),
    ])  # fmt: skip
    success(f"one reduced step equals the dense solution of all {len(x)} unknowns")


# --------------------------------------------------------------------- your bundle


def check_ray_partials(fn) -> None:
    """``fn(X, X0, R, dR, c) -> (xy, dX0, dangles, dX)``: image coordinates (n, 2) mm of n rays
    (x0 = y0 = 0) and their partial derivatives (n, 2, 3) by X0, (ω, φ, κ) and X; ``R`` (n, 3, 3)
    image → object, ``dR`` (3, n, 3, 3) its derivatives by ω, φ, κ."""
    rng = rng_for("lesson10.check_ray_partials")
    n = 5
    ang = rng.uniform(-0.2, 0.2, (n, 3))
    X0 = rng.normal(0.0, 50.0, (n, 3)) + [0.0, 0.0, 900.0]
    X = rng.normal(0.0, 200.0, (n, 3)) * [1.0, 1.0, 0.1]
    c = rng.uniform(100.0, 160.0, n)
    R = matrix_from_opk(ang[:, 0], ang[:, 1], ang[:, 2])
    dR = np.stack(matrix_derivatives(ang[:, 0], ang[:, 1], ang[:, 2]))
    with own_work(collinearity=collinearity):
        got = call(fn, X.copy(), X0.copy(), R.copy(), dR.copy(), c.copy(), what="ray_partials")
    if not isinstance(got, tuple) or len(got) != 4:
        raise CheckFailed("ray_partials: return the four results (xy, dX0, dangles, dX)")

    def proj(X, X0, ang):  # oracle: the collinearity equations, written out
        Rm = matrix_from_opk(ang[:, 0], ang[:, 1], ang[:, 2])
        uvw = np.einsum("nki,nk->ni", Rm, X - X0)
        return -c[:, None] * uvw[:, :2] / uvw[:, 2:]

    def numeric(which):  # central differences, one coordinate at a time
        out = np.zeros((n, 2, 3))
        for k in range(3):
            h = 1e-6 if which == "ang" else 1e-3
            e = np.zeros((n, 3))
            e[:, k] = h
            args = {"X": (X, X0, ang), "X0": (X, X0, ang), "ang": (X, X0, ang)}[which]
            plus, minus = [list(args), list(args)]
            i = {"X": 0, "X0": 1, "ang": 2}[which]
            plus[i], minus[i] = args[i] + e, args[i] - e
            out[:, :, k] = (proj(*plus) - proj(*minus)) / (2 * h)
        return out

    xy, dX0, dang, dX = (np.asarray(g, dtype=float) for g in got)
    compare("xy [mm]", xy, proj(X, X0, ang), rtol=1e-10, wrong=[
        ("R is applied instead of Rᵀ: (u, v, w)ᵀ = Rᵀ (X − X0)",
         -c[:, None] * np.einsum("nik,nk->ni", R, X - X0)[:, :2] / np.einsum("nik,nk->ni", R, X - X0)[:, 2:]),
    ])  # fmt: skip
    want_X = numeric("X")
    no_w = (
        -(c / np.einsum("nki,nk->ni", R, X - X0)[:, 2])[:, None, None]
        * np.transpose(R, (0, 2, 1))[:, :2]
    )
    compare("∂(x, y)/∂X [mm/m]", dX, want_X, rtol=1e-6, wrong=[
        ("the quotient rule lost its second term: ∂(u/w) = (∂u − (u/w) ∂w)/w", no_w),
        ("the sign is wrong: ∂x/∂X = −c/w (∂u/∂X − (u/w) ∂w/∂X)", -want_X),
    ])  # fmt: skip
    compare("∂(x, y)/∂X0 [mm/m]", dX0, numeric("X0"), rtol=1e-6, wrong=[
        ("∂/∂X0 = −∂/∂X: X0 enters as X − X0", -numeric("X0")),
    ])  # fmt: skip
    compare("∂(x, y)/∂(ω, φ, κ) [mm/rad]", dang, numeric("ang"), rtol=1e-6, wrong=[
        ("the sign is wrong: ∂x/∂ω = −c/w (∂u/∂ω − (u/w) ∂w/∂ω)", -numeric("ang")),
    ])  # fmt: skip

    def proj_c(X_, X0_, ang_):  # the same equations, complex-safe (Rodrigues), for the complex step
        R_ = np.stack([_rodrigues_opk(*a, unit=1.0) for a in ang_])
        uvw = np.einsum("nki,nk->ni", R_, X_ - X0_)
        return -c[:, None] * uvw[:, :2] / uvw[:, 2:]

    for name, g, exact in (
        ("∂(x, y)/∂X", dX, complex_step(lambda q: proj_c(q, X0, ang), X)),
        ("∂(x, y)/∂X0", dX0, complex_step(lambda q: proj_c(X, q, ang), X0)),
        ("∂(x, y)/∂(ω, φ, κ)", dang, complex_step(lambda q: proj_c(X, X0, q), ang)),
    ):
        exact_derivatives(name, g, np.einsum("iaib->iab", exact))
    success(
        "xy and all 9 partial derivatives of 5 rays agree with central differences and, to "
        "round-off, with their complex-step derivatives"
    )


_LIBRARY_BUNDLE = {
    "reference_bundle": reference_bundle,
    "linearise": linearise,
    "normal_equations": normal_equations,
    "bundle_adjust": bundle_adjust,
}


def _bundle_case(fn, block, control: str):
    """Run the student's bundle on ``block`` with the control ``"fixed"`` or ``"weighted"``;
    return its result and the library's adjustment of the same block."""
    data = reference_data(block, control)
    with own_work(**_LIBRARY_BUNDLE):
        got = call(fn, data, block.images.X0.copy(), block.images.angles.copy(),
                   data.xyz0.copy(), what="my_bundle")  # fmt: skip
    if not isinstance(got, tuple) or len(got) < 5:
        raise CheckFailed("my_bundle: return (X0, angles, xyz, sigma0, history, ...)")
    return data, got, bundle_adjust(block, control=control)


def _compare_bundle(block, data, got, adj, label: str) -> float:
    X0, angles, s0 = (np.asarray(got[k], dtype=float) for k in (0, 1, 3))
    eo = adj.x[adj.groups["exterior"]].reshape(-1, 6)
    sd = adj.std()[adj.groups["exterior"]].reshape(-1, 6)
    m, n = block.n_images, data.image.size
    p = data.unknown.size
    r = adj.redundancy
    n_prior = int(np.count_nonzero(data.prior_w))
    wrong = [
        ("the points held fixed (control) are no unknowns: r = 2·rays − 6·images − 3·unknown points",
         adj.sigma0 * np.sqrt(r / (r - 3 * (block.n_points - p)))),
        ("vᵀPv divided by the number of observations, not the redundancy", adj.sigma0 * np.sqrt(r / (2 * n))),
        ("the square root is missing (σ̂0² = vᵀPv / r)", adj.sigma0**2),
    ]  # fmt: skip
    if n_prior:
        wrong.append(("the observed control coordinates are observations too: r = 2·rays + "
                      "control coordinates − 6·images − 3·points",
                      adj.sigma0 * np.sqrt(r / (r - n_prior))))  # fmt: skip
    compare(f"σ̂0 ({label})", float(s0), adj.sigma0, rtol=1e-4, wrong=wrong)
    if X0.shape != (m, 3) or angles.shape != (m, 3):
        raise CheckFailed(
            f"X0 and angles: expected shapes ({m}, 3), got {X0.shape}, {angles.shape}"
        )
    off = np.abs(np.hstack([X0, angles]) - eo) / sd
    compare(f"stations in units of their σ ({label})", float(off.max()), 0.0, rtol=0.01, scale=1.0)
    return float(off.max())


def check_my_bundle(fn) -> None:
    """``fn(data, X0, angles, xyz) -> (X0, angles, xyz, sigma0, history, ...)``: the whole
    bundle iteration on the rays, weights and datum of ``data``
    (:func:`orientviz.bundle.reference.reference_data`), from the start values given.

    Two blocks: control held fixed (the control points are no unknowns) and control observed
    with σ (their coordinates are weighted observations: the datum). Oracle: the library's
    ``bundle_adjust`` of the same block, which the student's function must not call (nor the
    reference path of the lesson). The history must end with a step below the default
    ``tol`` = 0.005.
    """
    seed = int(rng_for("lesson10.check_my_bundle").integers(1000))
    block = simulate_block(2, 4, rng=seed, extra=None).block
    data, got, adj = _bundle_case(fn, block, "fixed")
    off = _compare_bundle(block, data, got, adj, "control held fixed")
    history = list(got[4])
    tol = 5e-3
    if not history or float(history[-1][1]) >= tol:
        raise CheckFailed(
            "my_bundle: the history must end with a step whose largest correction is below tol "
            f"(in units of its σ); got {history[-1][1] if history else 'no steps'}",
            error=np.inf, tolerance=0.0,
        )  # fmt: skip
    weighted = block.copy()
    control = np.all(np.nan_to_num(weighted.points.sigma, nan=1.0) == 0.0, axis=1)
    weighted.points.sigma[control] = [0.02, 0.03, 0.05]  # m: unequal, so a lost weight shows
    try:
        data_w, got_w, adj_w = _bundle_case(fn, weighted, "weighted")
        off_w = _compare_bundle(weighted, data_w, got_w, adj_w, "control observed with σ")
    except CheckFailed as exc:
        if "control coordinates − 6·images" in str(exc):
            raise
        raise CheckFailed(
            f"my_bundle is right with the control held fixed, but not with the control observed "
            f"with σ — the control coordinates are observations: add P_control to V and "
            f"P_control·(X_given − X) to b_p (and their vᵀPv to σ̂0). Without them the block "
            f"has no datum. ({str(exc).lstrip('✗ ')})",
            error=np.inf, tolerance=0.0,
        ) from None  # fmt: skip
    success(f"σ̂0 = {float(got[3]):.4f} and {float(got_w[3]):.4f} (control fixed / observed) as "
            f"the library's; stations within {max(off, off_w):.1e} σ; "
            f"{len(history)} steps")  # fmt: skip


def check_point_covariance(fn) -> None:
    """``fn(U, W, V, j) -> Q (3, 3)``: the cofactor block of point j from the normal-equation
    blocks (U (6m, 6m), W (6m, 3p), V (p, 3, 3) one block per point), without inverting the
    whole matrix."""
    rng = rng_for("lesson10.check_point_covariance")
    U, W, Vf, _, _ = _system(rng, m=3, q=6)
    m, q = U.shape[0] // 6, Vf.shape[0] // 3
    V = np.stack([Vf[3 * k : 3 * k + 3, 3 * k : 3 * k + 3] for k in range(q)])
    N = np.block([[U, W], [W.T, Vf]])
    j = 4
    want = np.linalg.inv(N)[6 * m + 3 * j : 6 * m + 3 * j + 3, 6 * m + 3 * j : 6 * m + 3 * j + 3]
    with small_matrices(
        6 * m,
        "that is the whole N inverted; the exercise needs only S (6m × 6m) and the point's own "
        "3 × 3 block",
        **INVERTERS,
    ):
        got = call(fn, U.copy(), W.copy(), V.copy(), j, what="point_covariance")
    compare("Q of point j", got, want, rtol=1e-9, wrong=[
        ("V_j⁻¹ alone ignores the uncertainty of the orientations: add V_j⁻¹ W_jᵀ S⁻¹ W_j V_j⁻¹",
         np.linalg.inv(V[j])),
        ("the orientations' term is subtracted: their uncertainty ADDS to the point's, "
         "Q_jj = V_j⁻¹ + V_j⁻¹ W_jᵀ S⁻¹ W_j V_j⁻¹", 2 * np.linalg.inv(V[j]) - want),
    ])  # fmt: skip
    success("Q_jj equals the point's block of the whole inverse N⁻¹")


def _rms_image_residual_um(data, X0, angles, xyz) -> float:
    """RMS of l − f(x) over all rays' x and y (µm), the collinearity equations image by image."""
    c, x0, y0 = (np.asarray(a, dtype=float) for a in data.cam)
    e = np.zeros((data.image.size, 2))
    for i in range(len(X0)):
        m = data.image == i
        R = matrix_from_opk(*np.asarray(angles, dtype=float)[i])
        uvw = (np.asarray(xyz, dtype=float)[data.point[m]] - X0[i]) @ R  # Rᵀ (X − X0) per row
        xy = np.column_stack(
            [x0[m] - c[m] * uvw[:, 0] / uvw[:, 2], y0[m] - c[m] * uvw[:, 1] / uvw[:, 2]]
        )
        e[m] = data.l[m] - xy
    return float(np.sqrt(np.mean(e**2)) * 1000.0)


def check_first_state_below(answer: object, data, states, limit_um: float = 10.0) -> None:
    """The first state k (0 = the start) of the student's iteration whose RMS image residual
    is below ``limit_um``; ``states`` lists (X0, angles, xyz, ...) per state (the slider's).

    Oracle: the collinearity equations evaluated here for every ray of ``data``
    (:func:`orientviz.bundle.reference.reference_data`), not the viewer's misclosure.
    """
    got = answer_value(answer, f"first state below {limit_um:g} µm")
    if got is None:
        raise NotWrittenError(
            f"first state below {limit_um:g} µm: not written yet (type the state you read off the slider)"
        )
    rms = [_rms_image_residual_um(data, *st[:3]) for st in states]
    want = next((k for k, r in enumerate(rms) if r < limit_um), None)
    if want is None:  # pragma: no cover - the lesson's iteration gets there
        raise CheckFailed(f"no state is below {limit_um:g} µm (smallest {min(rms):.1f} µm)")
    if got == want:
        success(f"state {want}: RMS {rms[want]:.2f} µm (state {want - 1}: {rms[want - 1]:.1f} µm)")
        return
    k = int(got)
    if 0 <= k < len(rms) and got == k:
        why = (f"state {k} has {rms[k]:.2f} µm — " + ("not yet below" if rms[k] >= limit_um
               else f"below, but state {want} already is"))  # fmt: skip
    else:
        why = f"the states are numbered 0 … {len(rms) - 1} (0: the start, before any step)"
    raise CheckFailed(
        f"first state below {limit_um:g} µm: {got:g} — {why}", error=np.inf, tolerance=0.0
    )


# --------------------------------------------------------------------- patterns of S and L


def check_coupled(fn) -> None:
    """``fn(image, point, m) -> P (m, m) bool``: the non-zero 6 × 6 blocks of the reduced
    matrix S of a block whose rays are ``(image[k], point[k])`` (point −1: a fixed point).

    Oracle: S = U − W V⁻¹ Wᵀ formed numerically from random blocks with that structure and
    its non-zero blocks read off — not the library's ``reduced_pattern``.
    """
    rng = rng_for("lesson10.check_coupled")
    m, q, n = 7, 12, 30
    image = rng.integers(0, m, n)
    point = rng.integers(-1, q, n)  # some rays to fixed points (−1)
    h = q // 2  # image 0 sees only points < h, image m − 1 only points ≥ h: not coupled …
    first, last = (image == 0) & (point >= h), (image == m - 1) & (point >= 0) & (point < h)
    point[first], point[last] = point[first] % h, h + point[last] % (q - h)
    image, point = np.r_[image, 0, m - 1], np.r_[point, -1, -1]  # … but both see a fixed point
    point[image == 3] = -1  # image 3 sees fixed points only: it couples nothing, but U_3 is there
    image, point = np.r_[image, 3], np.r_[point, -1]
    U = np.zeros((6 * m, 6 * m))
    W = np.zeros((6 * m, 3 * q))
    V = np.zeros((3 * q, 3 * q))
    for i, j in zip(image, point):
        J = rng.normal(size=(2, 9))
        U[6 * i : 6 * i + 6, 6 * i : 6 * i + 6] += J[:, :6].T @ J[:, :6]
        if j >= 0:
            W[6 * i : 6 * i + 6, 3 * j : 3 * j + 3] += J[:, :6].T @ J[:, 6:]
            V[3 * j : 3 * j + 3, 3 * j : 3 * j + 3] += J[:, 6:].T @ J[:, 6:]
    U += np.eye(6 * m)
    V += np.eye(3 * q)
    S = U - W @ np.linalg.solve(V, W.T)
    want = np.abs(S).reshape(m, 6, m, 6).max(axis=(1, 3)) > 1e-12
    with own_work(reduced_pattern=reduced_pattern):
        got = call(fn, image.copy(), point.copy(), m, what="coupled")
    got = np.asarray(got)
    if got.shape != (m, m):
        raise CheckFailed(f"coupled: expected an (m, m) = ({m}, {m}) pattern, got {got.shape}")
    got = got.astype(bool)
    if np.array_equal(got, want):
        success(f"the pattern of S: {int(want.sum())} of {m * m} blocks, from the rays alone")
        return
    no_diag = want & ~np.eye(m, dtype=bool)
    seen = np.zeros((m, q), bool)
    ok = point >= 0
    seen[image[ok], point[ok]] = True
    with_fixed = np.zeros((m, q + 1), bool)
    with_fixed[image, point] = True  # −1 lands in the last column
    wrong = {
        "the diagonal blocks U_i are never zero (every image that has a ray)": no_diag,
        "the diagonal: U_i = Σ AᵀPA is there for every image, even one that sees only fixed "
        "points (image 3 here)": want & ~np.eye(m, dtype=bool) | np.diag(seen.any(axis=1)),
        "a fixed point (−1) is no unknown: it couples nothing": (with_fixed.astype(int) @ with_fixed.T.astype(int)) > 0,
        "only one triangle: S is symmetric": np.triu(want),
    }  # fmt: skip
    why = next((w for w, v in wrong.items() if np.array_equal(got, v)),
               "images i and k are coupled if they see a common unknown point")  # fmt: skip
    raise CheckFailed(f"coupled: {int((got != want).sum())} blocks wrong — {why}",
                      error=np.inf, tolerance=0.0)  # fmt: skip


def check_fill_pattern(fn) -> None:
    """``fn(P) -> L (n, n) bool``: the non-zeros of the lower Cholesky factor of a symmetric
    positive definite matrix with the non-zero pattern P (diagonal included).

    Oracle: numpy's Cholesky factor of random matrices with that pattern (three patterns, the
    non-zeros read off) — not the library's ``cholesky_fill``.
    """
    rng = rng_for("lesson10.check_fill_pattern")
    for n, dens in ((9, 0.25), (12, 0.15), (10, 0.3)):
        A = rng.random((n, n)) < dens
        P = A | A.T | np.eye(n, dtype=bool)
        M = np.where(P, rng.normal(size=(n, n)), 0.0)
        M = (M + M.T) / 2 + np.diag(np.full(n, 3.0 * n))  # symmetric, diagonally dominant
        L = np.linalg.cholesky(M)
        want = np.abs(L) > 1e-12 * np.abs(L).max()
        with own_work(cholesky_fill=cholesky_fill):
            got = np.asarray(call(fn, P.copy(), what="fill_pattern"))
        if got.shape != (n, n):
            raise CheckFailed(f"fill_pattern: expected an ({n}, {n}) pattern, got {got.shape}")
        got = got.astype(bool)
        if np.array_equal(got, want):
            continue
        first = np.array([np.flatnonzero(P[i])[0] for i in range(n)])
        envelope = np.tril(np.arange(n)[None, :] >= first[:, None])
        wrong = {
            "no fill-in at all: eliminating column k makes every pair of its rows below k "
            "non-zero in L": np.tril(P),
            "the whole envelope: it is only an upper bound — a zero inside it stays zero when "
            "no earlier column has non-zeros in both rows": envelope,
            "L is lower triangular: the upper half is zero": want | want.T,
        }  # fmt: skip
        why = next((w for w, v in wrong.items() if np.array_equal(got, v)),
                   "eliminating column k links every pair of rows below k that are non-zero in it")  # fmt: skip
        raise CheckFailed(f"fill_pattern ({n} × {n}): {int((got != want).sum())} entries wrong — {why}",
                          error=np.inf, tolerance=0.0)  # fmt: skip
    success("the fill-in of three patterns equals numpy's Cholesky factors")
