"""Checkers for lesson 06 (epipolar geometry and normalised images).

Oracles: error-free simulated pairs (known R1, R2, B, model points): coplanarity of the
true rays; the epipolar line checked by brute force — two points on the left ray at
different depths projected into the right image must lie on it; model points compared
with the simulated truth.
"""

from __future__ import annotations

import numpy as np

from ..camera import project
from ..orientation.essential import eight_point  # forbidden in eight_point_mine, no oracle
from ..rotation import matrix_from_opk, skew
from ._common import (
    CheckFailed,
    call,
    check_determined_table,
    compare,
    own_work,
    rng_for,
    success,
)


def _pair(rng):
    c = rng.uniform(100.0, 160.0)
    b = rng.uniform(70.0, 100.0)
    B = np.array([b, rng.uniform(-4, 4), rng.uniform(-4, 4)])
    R2 = matrix_from_opk(*rng.uniform(-0.05, 0.05, 3))
    n = 8
    P = np.column_stack(
        [rng.uniform(-10, b + 10, n), rng.uniform(-80, 80, n), -c + rng.uniform(-20, 20, n)]
    )
    xy1 = project(P, np.zeros(3), np.eye(3), c)
    xy2 = project(P, B, R2, c)
    return c, B, R2, P, xy1, xy2


# --------------------------------------------------------------------- E


def check_plane_points(fn) -> None:
    """``fn(n_plane, n_off) -> bool``: do ``n_plane`` matches of points on one plane and
    ``n_off`` matches of points in general position determine E by the (linear) eight-point
    algorithm? Oracle: the rank of the checker's own n × 9 system for every combination of
    0–12 and 0–9 points (rank 8: E fixed up to its scale)."""
    rng = rng_for("lesson06.check_plane_points")
    c, b = 152.0, 90.0
    R2, B = matrix_from_opk(0.02, -0.03, 0.05), np.array([b, 2.0, -1.0])
    cases = [(p, q) for p in range(13) for q in range(10)]
    truth, got = [], []
    for n_plane, n_off in cases:
        P1 = np.column_stack([rng.uniform(-5, b + 5, n_plane), rng.uniform(-90, 90, n_plane),
                              np.zeros(n_plane)])  # fmt: skip
        P1[:, 2] = -c + 0.1 * P1[:, 0] - 0.05 * P1[:, 1]  # one (tilted) plane
        P2 = np.column_stack([rng.uniform(-5, b + 5, n_off), rng.uniform(-90, 90, n_off),
                              -c + rng.uniform(-15, 15, n_off)])  # fmt: skip
        P = np.vstack([P1, P2])
        rank = 0
        if len(P):
            d1 = np.column_stack([project(P, np.zeros(3), np.eye(3), c), np.full(len(P), -c)])
            d2 = np.column_stack([project(P, B, R2, c), np.full(len(P), -c)])
            sv = np.linalg.svd((d1[:, :, None] * d2[:, None, :]).reshape(-1, 9), compute_uv=False)
            rank = int(np.sum(sv > 1e-9 * sv[0]))
        truth.append(rank == 8)
        answer = call(fn, n_plane, n_off, what="determined")
        if not isinstance(answer, (bool, np.bool_)):
            raise CheckFailed(
                f"determined{(n_plane, n_off)}: expected True or False, got {answer!r}"
            )
        got.append(bool(answer))
    rules = [
        ("counting points is not enough: matches of points on one plane give at most six "
         "independent equations (their images are related by a homography)",
         lambda p, q: p + q >= 8),
        ("points on a plane do help — up to six equations; two points off the plane complete them",
         lambda p, q: q >= 8),
        ("E has nine entries fixed up to a scale: the linear algorithm needs eight independent "
         "equations, not seven", lambda p, q: min(p, 6) + q >= 7),
    ]  # fmt: skip
    check_determined_table(got, truth, cases, rules, labels="on the plane, off it",
                           what="configurations", rank="the system has rank 8")  # fmt: skip
    success(f"all {len(cases)} combinations of 0–12 points on a plane and 0–9 off it right")


# --------------------------------------------------------------------- the epipole


def _epipole_pairs(rng):
    """Three error-free pairs whose right epipole lies at a finite, measurable place: a base
    with a clear b_z (a convergent or stepped pair), κ and φ of a few gon; (E, c, B, R2)."""
    out = []
    for bz in (35.0, -60.0, 18.0):
        c = rng.uniform(100.0, 160.0)
        B = np.array([rng.uniform(60.0, 100.0), rng.uniform(-15.0, 15.0), bz])
        R2 = matrix_from_opk(*rng.uniform(-0.08, 0.08, 3))
        out.append((skew(B) @ R2, c, B, R2))
    return out


def _image_of(direction, c):
    """Image point (mm) of a ray direction in a camera frame whose image plane is z = −c."""
    return -c * direction[:2] / direction[2]


def check_epipole(fn) -> None:
    """``fn(E, c) -> (x, y)``: the epipole of the right image (mm), the image there of the
    left projection centre, from E alone (E = [B]× R2, any scale and sign)."""
    for k, (E, c, B, R2) in enumerate(_epipole_pairs(rng_for("lesson06.check_epipole"))):
        # oracle: the left projection centre (the model origin) projected into the right image
        truth = project(np.zeros((1, 3)), B, R2, c)[0]
        scale = float(np.abs(E).max())
        got = call(fn, E.copy() * (-1.7 if k == 1 else 1.0) / scale, c, what="epipole")
        wrong = [
            ("this is the LEFT epipole (the image of the right centre in the left image): "
             "Eᵀ d1 = 0, i.e. the null vector of Eᵀ; the right one solves E d2 = 0",
             _image_of(B, c)),
            ("the sign is reversed: x = −c d_x/d_z, the image plane is at z = −c",
             -_image_of(R2.T @ B, c)),
            ("the factor −c is missing: (d_x/d_z, d_y/d_z) is a direction, not mm in the image",
             (R2.T @ B)[:2] / (R2.T @ B)[2]),
            ("R2 instead of R2ᵀ: d2 = R2ᵀ B turns the base into the right image's frame",
             _image_of(R2 @ B, c)),
        ]  # fmt: skip
        compare(f"right epipole of pair {k + 1} [mm]", got, truth, rtol=1e-7, wrong=wrong)
    success("the right epipoles of three pairs (one with E scaled by −1.7) are the images of "
            "the left projection centres")  # fmt: skip


# --------------------------------------------------------------------- a swapped match


def check_swapped_pair(fn) -> None:
    """``fn(E, xy1, xy2, c) -> (i, j)``: the two matches whose right points were exchanged,
    in a pair that also holds one single wrong match (larger distance than the swap's)."""
    rng = rng_for("lesson06.check_swapped_pair")
    c, b, n = 152.0, 90.0, 30
    P = np.column_stack(
        [rng.uniform(0, b, n), rng.uniform(-90, 90, n), -c + rng.uniform(-15, 15, n)]
    )
    R2 = matrix_from_opk(*rng.uniform(-0.03, 0.03, 3))
    B = np.array([b, rng.uniform(-2, 2), rng.uniform(-2, 2)])
    xy1 = project(P, np.zeros(3), np.eye(3), c) + rng.normal(0, 0.002, (n, 2))
    xy2 = project(P, B, R2, c) + rng.normal(0, 0.002, (n, 2))
    Bx = np.array([[0.0, -B[2], B[1]], [B[2], 0.0, -B[0]], [-B[1], B[0], 0.0]])
    E = Bx @ R2

    def dist(a: np.ndarray, q: np.ndarray) -> np.ndarray:  # the checker's own epipolar distances
        g = np.column_stack([a, np.full(len(a), -c)]) @ E
        return (g[:, 0] * q[:, 0] + g[:, 1] * q[:, 1] - c * g[:, 2]) / np.hypot(g[:, 0], g[:, 1])

    i, j = (int(k) for k in rng.choice(n, 2, replace=False))
    while abs(xy2[i, 1] - xy2[j, 1]) < 40.0:
        i, j = (int(k) for k in rng.choice(n, 2, replace=False))
    xy2[[i, j]] = xy2[[j, i]]
    d = np.abs(dist(xy1, xy2))
    k = int(next(m for m in rng.permutation(n) if m not in (i, j)))
    xy2[k, 1] += 1.5 * max(d[i], d[j])  # a single wrong match, farther from its line
    d = np.abs(dist(xy1, xy2))
    got = call(fn, E.copy(), xy1.copy(), xy2.copy(), c, what="swapped_pair")
    try:
        pair = {int(g) for g in got}
    except (TypeError, ValueError):
        raise CheckFailed(f"swapped_pair: return two indices (i, j), got {got!r}") from None
    if pair == {i, j}:
        success(
            f"matches {min(i, j)} and {max(i, j)} were swapped; match {k} is a single wrong match"
        )
        return
    largest = {int(m) for m in np.argsort(d)[-2:]}
    if pair == largest:
        raise CheckFailed(
            f"swapped_pair: {sorted(pair)} are the two largest distances, but match {k} is a single "
            "wrong match, not half of the swap — exchange the right points of a candidate pair "
            "and keep the pair whose distances both vanish"
        )
    if k in pair:
        raise CheckFailed(
            f"swapped_pair: {sorted(pair)} contains match {k}, a single wrong match: exchanging its "
            "right point with another one does not clear both distances"
        )
    if pair == {i + 1, j + 1}:
        raise CheckFailed("swapped_pair: these are 1-based indices; numpy counts from 0")
    raise CheckFailed(f"swapped_pair: {sorted(pair)} is not the swapped pair")


@own_work(eight_point=eight_point)
def check_eight_point(fn) -> None:
    """``fn(xy1, xy2, c) -> E``: the essential matrix from n ≥ 8 matches (rays (x, y, −c)),
    rank 2 with singular values (1, 1, 0), ‖E‖ = √2; defined up to its sign."""
    rng = rng_for("lesson06.check_eight_point")
    c, B, R2, P, xy1, xy2 = _pair(rng)
    E = np.asarray(call(fn, xy1.copy(), xy2.copy(), c, what="eight_point_mine"), dtype=float)
    if E.shape != (3, 3):
        raise CheckFailed(f"eight_point_mine: expected E of shape (3, 3), got {E.shape}")
    truth = skew(B) @ R2
    truth = truth / np.linalg.norm(truth) * np.sqrt(2.0)
    sign = 1.0 if np.sum(E * truth) >= 0 else -1.0
    compare("E of an error-free pair (up to its sign)", sign * E, truth, rtol=1e-6, wrong=[
        ("E is transposed: the rows of the system are vec(d1 d2ᵀ) for d1ᵀ E d2 = 0", truth.T),
        ("E is transposed: the rows of the system are vec(d1 d2ᵀ) for d1ᵀ E d2 = 0", -truth.T),
        ("E is not scaled to ‖E‖ = √2", truth / np.sqrt(2.0)),
    ])  # fmt: skip
    # noisy matches: only properties can be checked without the answer itself
    n1 = xy1 + rng.normal(0, 0.004, xy1.shape)
    n2 = xy2 + rng.normal(0, 0.004, xy2.shape)
    E = np.asarray(call(fn, n1, n2, c, what="eight_point_mine"), dtype=float)
    s = np.linalg.svd(E, compute_uv=False)
    if s.shape == (3,) and s[2] > 1e-6 * s[0]:
        raise CheckFailed(
            f"E from noisy matches has rank 3 (singular values {np.round(s, 6).tolist()}): force "
            "them to (1, 1, 0) — with noise the smallest one is not zero by itself",
            float(s[2] / s[0]),
            1e-8,
        )
    compare("singular values of E from noisy matches", s, [1.0, 1.0, 0.0], rtol=1e-8, scale=1.0,
            wrong=[])  # fmt: skip
    d1 = np.column_stack([n1, np.full(len(n1), -c)])
    d2 = np.column_stack([n2, np.full(len(n2), -c)])
    cop = np.abs(np.einsum("ni,ij,nj->n", d1, E, d2)).max() / (c * c)
    if cop > 1e-3:
        raise CheckFailed(f"E from noisy matches: the rays are far from coplanar (|d1ᵀ E d2|/c² = {cop:.2g})",
                          cop, 1e-5)  # fmt: skip
    success(
        "the true E comes back from error-free matches; from noisy ones E has rank 2, (1, 1, 0)"
    )
