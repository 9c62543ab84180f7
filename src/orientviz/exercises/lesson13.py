"""Checkers for lesson 13, auxiliary data (statoscope, APR, GNSS) in the adjustment.

Oracles: the normal equations of the stacked system formed from scratch, numerical
derivatives of the observation function, the offset model solved from scratch (for the
heights from differences), and the covariance of differences written by hand — never the library's
``auxiliary_rows`` or ``bundle_adjust(..., auxiliary=...)``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from orientviz.exercises._common import (
    INVERTERS,
    CheckFailed,
    call,
    compare,
    own_work,
    rng_for,
    small_matrices,
    success,
)


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
)
def check_from_differences(fn: Callable) -> None:
    """Check ``fn(A0, l0, sig0, s, sigma) -> Z``: the heights adjusted from the strip's rows
    (A0 (r, m), l0, sig0) together with the m − 1 consecutive differences of the statoscope
    readings s (σ each), with their covariance — no offset unknown.

    Oracle: the same data with the readings as observations s + v = Z_k + o and the offset
    as an unknown (the model of the lesson), solved from scratch; the two must agree exactly.
    Because they agree, the answer may not invert or solve with more than m = 9 unknowns
    (numpy's and scipy's inverses, solvers and least-squares fits are watched): solving the
    offset model again is refused.
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
