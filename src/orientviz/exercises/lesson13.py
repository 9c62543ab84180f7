"""Checkers for lesson 13, auxiliary data (statoscope, APR, GNSS) in the adjustment.

Oracles: the normal equations of the stacked system formed from scratch (one design row per
reading, for the bundle's bordered system too), central differences of the GNSS observation
with a lever arm, the offset model solved from scratch (for the heights from differences), and
the covariance of differences written by hand — never the library's ``auxiliary_rows`` or
``bundle_adjust(..., auxiliary=...)``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.linalg

from orientviz.exercises._common import (
    INVERTERS,
    CheckFailed,
    call,
    compare,
    complex_step,
    exact_derivatives,
    own_work,
    rng_for,
    small_matrices,
    success,
)
from orientviz.exercises.lesson02 import _rodrigues_opk
from orientviz.rotation import matrix_derivatives, matrix_from_opk

#: Factorisations and triangular solves: with :data:`INVERTERS` they are the routes to solve a
#: system, watched by :func:`check_from_differences` (a QR of the offset model and a triangular
#: solve would otherwise pass as "the differences").
_FACTORS = {
    "np.linalg.qr": np.linalg.qr,
    "np.linalg.cholesky": np.linalg.cholesky,
    "np.linalg.svd": np.linalg.svd,
    "np.linalg.eigh": np.linalg.eigh,
    "scipy.linalg.qr": scipy.linalg.qr,
    "scipy.linalg.cholesky": scipy.linalg.cholesky,
    "scipy.linalg.cho_factor": scipy.linalg.cho_factor,
    "scipy.linalg.lu_factor": scipy.linalg.lu_factor,
    "scipy.linalg.svd": scipy.linalg.svd,
    "scipy.linalg.eigh": scipy.linalg.eigh,
    "scipy.linalg.solve_triangular": scipy.linalg.solve_triangular,
}


def statoscope_row_library(
    N: np.ndarray, n: np.ndarray, k: int, o_col: int, s: float, sigma: float
) -> tuple[np.ndarray, np.ndarray]:
    """The lesson's stand-in for ``add_statoscope_row`` while the student's blank is empty:
    the normal equations ``(N, n)`` after the reading ``s`` (m, σ ``sigma`` m) of height
    ``k`` plus the offset in column ``o_col`` (never shown in the lesson;
    :func:`check_statoscope_row` refuses it)."""
    row = np.zeros(len(n))
    row[[k, o_col]] = 1.0
    weight = 1.0 / sigma**2
    return N + weight * np.outer(row, row), n + weight * s * row


@own_work(
    "that is the stand-in; the exercise is the one row of the reading, written into N and n by you",
    statoscope_row_library=statoscope_row_library,
)
def check_statoscope_row(fn: Callable) -> None:
    """Check ``fn(N, n, k, o_col, s, sigma) -> (N, n)``: add the row s + v = Z_k + o.

    The lesson's stand-in :func:`statoscope_row_library` is refused."""
    rng = rng_for("lesson13.check_statoscope_row")
    u, rows = 7, 12
    A0 = rng.normal(size=(rows, u))
    P0 = np.diag(rng.uniform(0.5, 4.0, rows))
    l0 = rng.normal(size=rows)
    N0, n0 = A0.T @ P0 @ A0, A0.T @ P0 @ l0
    k, o_col, s, sigma = 2, 6, 1843.7, 0.4
    a = np.zeros(u)
    a[k], a[o_col] = 1.0, 1.0
    A, l = np.vstack([A0, a]), np.r_[l0, s]  # oracle: the stacked system from scratch
    P = np.diag(np.r_[np.diag(P0), 1 / sigma**2])
    N_ref, n_ref = A.T @ P @ A, A.T @ P @ l
    out = call(fn, N0.copy(), n0.copy(), k, o_col, s, sigma, what="add_statoscope_row")
    try:
        N, n = (np.asarray(x, float) for x in out)
    except (TypeError, ValueError):
        raise CheckFailed("return the two updated arrays (N, n)") from None
    am = a.copy()
    am[o_col] = -1.0
    compare(
        "N",
        N,
        N_ref,
        rtol=1e-10,
        wrong=[
            ("the weight 1/σ² is missing", N0 + np.outer(a, a)),
            ("1/σ instead of 1/σ²", N0 + np.outer(a, a) / sigma),
            ("the offset enters with a minus sign (s = Z − o)", N0 + np.outer(am, am) / sigma**2),
            (
                "only the diagonal was updated: the row couples Z_k and the offset",
                N0 + np.diag(a) / sigma**2,
            ),
        ],
    )
    compare(
        "n",
        n,
        n_ref,
        rtol=1e-10,
        wrong=[
            ("the weight 1/σ² is missing in n", n0 + a * s),
            ("the sign of the reading is wrong in n", n0 - a * s / sigma**2),
        ],
    )
    success("N and n equal the normal equations of the stacked system")


def statoscope_normals_library(
    N11: np.ndarray,
    n1: np.ndarray,
    Z0: np.ndarray,
    o: np.ndarray,
    s: np.ndarray,
    image: np.ndarray,
    strip: np.ndarray,
    sigma: float,
) -> tuple[np.ndarray, np.ndarray]:
    """The lesson's stand-in for ``statoscope_normals`` while the student's blank is empty:
    the bundle's orientation block ``(N11, n1)`` (6 columns per image: X0, Y0, Z0, ω, φ, κ)
    bordered by one offset column per strip, with the statoscope readings ``s`` (m, σ
    ``sigma`` m) of the images ``image`` in the strips ``strip`` added at the current heights
    ``Z0`` and offsets ``o`` (m). :func:`check_statoscope_normals` refuses it."""
    u1 = len(n1)
    cols = np.column_stack([6 * np.asarray(image) + 2, u1 + np.asarray(strip)])
    N = np.zeros((u1 + len(o), u1 + len(o)))
    N[:u1, :u1] = N11
    n = np.r_[n1, np.zeros(len(o))]
    w = 1.0 / sigma**2
    misclosure = np.asarray(s) - np.asarray(Z0)[image] - np.asarray(o)[strip]
    for (a, b), d in zip(cols, misclosure):
        N[np.ix_([a, b], [a, b])] += w
        n[[a, b]] += w * d
    return N, n


@own_work(
    "that is the stand-in; the exercise is the statoscope's rows in the bundle's normal "
    "equations, written by you",
    statoscope_normals_library=statoscope_normals_library,
)
def check_statoscope_normals(fn: Callable) -> None:
    """Check ``fn(N11, n1, Z0, o, s, image, strip, sigma) -> (N, n)``: the bundle's
    orientation block bordered by the strips' offsets, with the readings s + v = Z0_k + o_j
    added at the current values (a Gauss-Newton step: n gets the misclosure).

    Oracle: the design rows of the readings (1 at Z0 of the image, 1 at the strip's offset)
    stacked under a random system and its normal equations formed from scratch. The lesson's
    stand-in :func:`statoscope_normals_library` is refused.
    """
    rng = rng_for("lesson13.check_statoscope_normals")
    m, ns = 5, 2
    u1 = 6 * m
    A0 = rng.normal(size=(40, u1))
    N11 = A0.T @ A0
    n1 = rng.normal(size=u1)
    Z0 = 1500.0 + rng.normal(0.0, 5.0, m)
    o = np.array([-3.1, 4.4])
    image = np.array([0, 1, 2, 3, 4, 2])  # image 2 read twice
    strip = np.array([0, 0, 1, 1, 1, 1])
    sigma = 0.4
    s = Z0[image] + o[strip] + rng.normal(0.0, 0.5, len(image)) + 0.8
    A = np.zeros((len(s), u1 + ns))  # oracle: one design row per reading
    A[np.arange(len(s)), 6 * image + 2] = 1.0
    A[np.arange(len(s)), u1 + strip] = 1.0
    misclosure = s - Z0[image] - o[strip]
    N_ref = np.zeros((u1 + ns, u1 + ns))
    N_ref[:u1, :u1] = N11
    N_ref += A.T @ A / sigma**2
    n_ref = np.r_[n1, np.zeros(ns)] + A.T @ misclosure / sigma**2
    out = call(fn, N11.copy(), n1.copy(), Z0.copy(), o.copy(), s.copy(), image.copy(),
               strip.copy(), sigma, what="statoscope_normals")  # fmt: skip
    try:
        N, n = (np.asarray(x, float) for x in out)
    except (TypeError, ValueError):
        raise CheckFailed("return the two bordered arrays (N, n)") from None
    if N.shape != N_ref.shape or n.shape != n_ref.shape:
        raise CheckFailed(
            f"statoscope_normals: expected N {N_ref.shape} and n {n_ref.shape} (the {u1} "
            f"orientation unknowns and one offset per strip), got {N.shape} and {n.shape}"
        )
    one = A.copy()  # one offset for the whole block
    one[:, u1 + 1] = 0.0
    one[:, u1] = 1.0
    z_col = A.copy()  # the reading put in the X0 column
    z_col[np.arange(len(s)), 6 * image + 2] = 0.0
    z_col[np.arange(len(s)), 6 * image] = 1.0
    compare("N", N, N_ref, rtol=1e-10, wrong=[
        ("the weight 1/σ² is missing", np.pad(N11, ((0, ns), (0, ns))) + A.T @ A),
        ("one offset for the whole block: each strip has its own", np.pad(N11, ((0, ns), (0, ns)))
         + one.T @ one / sigma**2),
        ("the reading is a height: column 6k + 2 (Z0), not 6k (X0)",
         np.pad(N11, ((0, ns), (0, ns))) + z_col.T @ z_col / sigma**2),
    ])  # fmt: skip
    compare("n", n, n_ref, rtol=1e-10, scale=float(np.max(np.abs(n_ref))), wrong=[
        ("n got the reading s itself: in the bundle the unknowns are corrections, so n gets "
         "the misclosure s − (Z0 + o) at the current values",
         np.r_[n1, np.zeros(ns)] + A.T @ s / sigma**2),
        ("the misclosure's sign: n gets (s − Z0 − o)/σ², the observed minus the computed",
         np.r_[n1, np.zeros(ns)] - A.T @ misclosure / sigma**2),
        ("the current offsets are missing from the misclosure: s − (Z0 + o)",
         np.r_[n1, np.zeros(ns)] + A.T @ (s - Z0[image]) / sigma**2),
    ])  # fmt: skip
    success(
        f"N and n bordered by {ns} offsets equal the stacked system's normal equations "
        "(the image read twice counted twice)"
    )


def check_gnss_lever_rows(fn: Callable) -> None:
    """Check ``fn(angles, e) -> (3, 6)``: the partial derivatives of the GNSS antenna
    position g = X0 + R(ω, φ, κ) e by (X0, Y0, Z0, ω, φ, κ) (angles in rad, lever arm e in
    the camera frame, m).

    Oracle: central differences of g computed with the rotation matrix, for two attitudes and
    lever arms (the derived partials of the library are not used).
    """
    rng = rng_for("lesson13.check_gnss_lever_rows")
    for angles, e in (
        (np.array([0.031, -0.052, 0.84]), np.array([0.42, -0.18, 1.35])),
        (rng.uniform(-0.3, 0.3, 3) + [0.0, 0.0, np.pi], np.array([-1.1, 0.6, 0.9])),
    ):
        want = np.zeros((3, 6))
        want[:, :3] = np.eye(3)
        h = 1e-6
        for k in range(3):
            dp, dm = angles.copy(), angles.copy()
            dp[k] += h
            dm[k] -= h
            want[:, 3 + k] = (matrix_from_opk(*dp) @ e - matrix_from_opk(*dm) @ e) / (2 * h)
        with own_work(
            "the partials of R are yours to write (lesson 02); the library's derivatives "
            "stand in nowhere here",
            matrix_derivatives=matrix_derivatives,
        ):
            got = call(fn, angles.copy(), e.copy(), what="gnss_lever_rows")
        R = matrix_from_opk(*angles)
        no_arm = want.copy()
        no_arm[:, 3:] = 0.0
        transposed = want.copy()
        for k in range(3):
            dp, dm = angles.copy(), angles.copy()
            dp[k] += h
            dm[k] -= h
            transposed[:, 3 + k] = (matrix_from_opk(*dp).T @ e - matrix_from_opk(*dm).T @ e) / (
                2 * h
            )
        kappa_left = want.copy()
        ez = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
        kappa_left[:, 5] = ez @ R @ e
        compare(f"∂g/∂(X0, Y0, Z0, ω, φ, κ) at {np.round(angles, 3).tolist()} rad", got, want,
                rtol=1e-6, scale=1.0, wrong=[
                    ("the angle columns are zero: the lever arm turns with the camera, so the "
                     "antenna moves when ω, φ or κ change", no_arm),
                    ("Rᵀe: R turns camera vectors into the object frame, the antenna is at "
                     "X0 + R e", transposed),
                    ("the angle columns have the wrong sign", want * [1, 1, 1, -1, -1, -1]),
                    ("∂R/∂κ = R[e_Z]×: κ is the last rotation, about the camera's z axis, not "
                     "the object's Z", kappa_left),
                ])  # fmt: skip
        exact = np.zeros((3, 6))
        exact[:, :3] = np.eye(3)
        exact[:, 3:] = complex_step(lambda a, e=e: _rodrigues_opk(*a, unit=1.0) @ e, angles)
        exact_derivatives("∂g/∂(X0, Y0, Z0, ω, φ, κ)", got, exact)
    success(
        "the GNSS rows with a lever arm agree with numerical derivatives at two attitudes "
        "and, to round-off, with exact ones"
    )


def check_difference_covariance(fn: Callable) -> None:
    """Check ``fn(sigma, m) -> C``: covariance of the m − 1 differences of m equal-σ readings."""
    for sigma, m in ((0.3, 6), (1.2, 4)):
        C = np.zeros((m - 1, m - 1))  # oracle: written by hand
        for i in range(m - 1):
            C[i, i] = 2 * sigma**2
            if i + 1 < m - 1:
                C[i, i + 1] = C[i + 1, i] = -(sigma**2)
        got = call(fn, sigma, m, what="difference_covariance")
        compare(
            f"C (σ = {sigma}, m = {m})",
            got,
            C,
            rtol=1e-12,
            wrong=[
                (
                    "the differences are not independent: neighbours share a reading",
                    2 * sigma**2 * np.eye(m - 1),
                ),
                ("each difference has the variance 2σ², not σ²", C / 2),
                ("neighbouring differences are negatively correlated", np.abs(C)),
            ],
        )
    success("covariance of consecutive differences: 2σ² on the diagonal, −σ² beside it")


def check_gnss_rows(fn: Callable) -> None:
    """Check ``fn(k, t, strip, m, n_strips) -> A (3, u)``: ∂(X0_k + o_s + t d_s)/∂x.

    Unknowns x = [X0 of the m images (m × 3, image-major), offsets (n_strips × 3),
    drifts (n_strips × 3)].
    """
    m, n_strips = 5, 3
    u = 3 * m + 6 * n_strips
    rng = rng_for("lesson13.check_gnss_rows")
    x = rng.normal(size=u)

    def f(x, k, t, s):  # the observation function, written out
        X0 = x[: 3 * m].reshape(m, 3)
        o = x[3 * m : 3 * m + 3 * n_strips].reshape(n_strips, 3)
        d = x[3 * m + 3 * n_strips :].reshape(n_strips, 3)
        return X0[k] + o[s] + t * d[s]

    for k, t, s in ((3, 42.5, 2), (0, -7.0, 1)):
        J = np.empty((3, u))  # oracle: central differences
        for j in range(u):
            e = np.zeros(u)
            e[j] = 1e-3
            J[:, j] = (f(x + e, k, t, s) - f(x - e, k, t, s)) / 2e-3
        got = call(fn, k, t, s, m, n_strips, what="gnss_rows")
        no_drift = J.copy()
        no_drift[:, 3 * m + 3 * n_strips :] = 0
        compare(
            f"rows of image {k} (t = {t} s, strip {s})",
            got,
            J,
            rtol=1e-8,
            wrong=[
                ("the drift columns are missing (offset only)", no_drift),
                ("the drift column holds 1, not the time t", np.where(np.isclose(J, t), 1.0, J)),
                (
                    "the offset enters with the wrong sign (the GNSS reads X0 + offset + t · drift)",
                    J * np.r_[np.ones(3 * m), -np.ones(3 * n_strips), np.ones(3 * n_strips)],
                ),
                (
                    "the offset and drift columns of another strip: strip s owns the columns "
                    "3m + 3s … and 3m + 3·n_strips + 3s …",
                    np.column_stack(
                        [J[:, : 3 * m]]
                        + [
                            np.roll(
                                J[:, 3 * m + 3 * n_strips * h : 3 * m + 3 * n_strips * (h + 1)],
                                3,
                                axis=1,
                            )
                            for h in (0, 1)
                        ]
                    ),
                ),
            ],
        )
    success("the three GNSS rows have 1 at X0, Y0, Z0 and the strip's offsets, t at its drifts")


@small_matrices(
    9,
    "an inverse or a solve with more unknowns than the 9 heights is the offset model again (its "
    "offset the 10th unknown); the exercise is the heights from the differences, no offset",
    **INVERTERS,
    **_FACTORS,
)
def check_from_differences(fn: Callable) -> None:
    """Check ``fn(A0, l0, sig0, s, sigma) -> Z``: the heights adjusted from the strip's rows
    (A0 (r, m), l0, sig0) together with the m − 1 consecutive differences of the statoscope
    readings s (σ each), with their covariance — no offset unknown.

    Oracle: the same data with the readings as observations s + v = Z_k + o and the offset
    as an unknown (the model of the lesson), solved from scratch; the two must agree exactly.
    Because they agree, the answer may not invert, solve or factor with more than m = 9
    unknowns (numpy's and scipy's inverses, solvers, least-squares fits, QR, Cholesky, LU,
    SVD, eigh and triangular solves are watched): solving the offset model again is refused.
    """
    rng = rng_for("lesson13.check_from_differences")
    m = 9
    A0 = np.zeros((m + 1, m))
    A0[np.arange(m - 1), np.arange(1, m)], A0[np.arange(m - 1), np.arange(m - 1)] = 1.0, -1.0
    A0[m - 1, 0] = A0[m, m - 1] = 1.0
    Z = 1500.0 + np.cumsum(rng.normal(0.0, 4.0, m))
    sig0 = np.r_[rng.uniform(0.3, 0.8, m - 1), 0.1, 0.15]
    l0 = A0 @ Z + rng.normal(0.0, 1.0, m + 1) * sig0
    sigma = 0.3
    s = Z - 6.2 + rng.normal(0.0, sigma, m)
    # oracle: the readings s + v = Z_k + o with the offset as an unknown, stacked and solved
    A = np.vstack(
        [np.column_stack([A0, np.zeros(m + 1)]), np.column_stack([np.eye(m), np.ones(m)])]
    )
    w = np.r_[1 / sig0**2, np.full(m, 1 / sigma**2)]
    want = np.linalg.solve(A.T @ (w[:, None] * A), A.T @ (w * np.r_[l0, s]))[:m]
    got = call(fn, A0.copy(), l0.copy(), sig0.copy(), s.copy(), sigma, what="from_differences")
    D = np.eye(m)[1:] - np.eye(m)[:-1]
    N0, n0 = A0.T @ (A0 / sig0[:, None] ** 2), A0.T @ (l0 / sig0**2)

    def with_weight(W):  # the differences with the weight matrix W
        return np.linalg.solve(N0 + D.T @ W @ D, n0 + D.T @ W @ (D @ s))

    wrong = [
        ("the differences taken as independent (2σ² each): neighbours share a reading, "
         "Cov = −σ²", with_weight(np.eye(m - 1) / (2 * sigma**2))),
        ("the covariance itself used as the weight: P = C⁻¹", with_weight(sigma**2 * D @ D.T)),
        ("the readings as heights without the offset", np.linalg.solve(
            N0 + np.eye(m) / sigma**2, n0 + s / sigma**2)),
    ]  # fmt: skip
    compare("Z from the differences [m]", got, want, rtol=1e-9, scale=1.0, wrong=wrong)
    success("the differences with their covariance give exactly the heights of the offset model")
