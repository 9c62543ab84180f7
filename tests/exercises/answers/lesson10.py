"""Lesson 10: the solutions of its exercises and the plausible wrong answers (mutants).

Kept out of the installed package (solutions stay with the teacher); used by
``tests/exercises/test_lesson10.py``.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import block_diag

import orientviz as ov
from orientviz.rotation import matrix_derivatives


def _coupled(image, point, m, mistake=None):
    P = np.eye(m, dtype=bool)
    for j in np.unique(point[point >= 0] if mistake != "fixed" else point):
        ims = np.unique(image[point == j])
        P[np.ix_(ims, ims)] = True
    if mistake == "no diagonal":
        P &= ~np.eye(m, dtype=bool)
    if mistake == "diagonal only where an unknown point is seen":
        P = np.zeros((m, m), dtype=bool)
        for j in np.unique(point[point >= 0]):
            ims = np.unique(image[point == j])
            P[np.ix_(ims, ims)] = True
    return np.triu(P) if mistake == "one triangle" else P


def _fill_pattern(P, mistake=None):
    n = len(P)
    L = np.tril(P).copy()
    if mistake == "no fill":
        return L
    if mistake == "envelope":
        first = np.array([np.flatnonzero(P[i])[0] for i in range(n)])
        return np.tril(np.arange(n)[None, :] >= first[:, None])
    for k in range(n):
        rows = np.flatnonzero(L[k + 1 :, k]) + k + 1
        L[np.ix_(rows, rows)] |= np.tril(np.ones((rows.size, rows.size), bool))
    return L


def _predicted_bandwidth(strips, per_strip, mistake=None):
    # along: image 0 of a strip meets the last image of the next strip (flown back); across:
    # two bases ahead in the neighbouring strip
    along, across = 2 * per_strip - 1, 2 * strips + 1
    if mistake == "same_direction":
        along = per_strip + 2
    if mistake == "across_2s":
        across = 2 * strips
    if mistake == "swapped":
        along, across = across, along
    return along, across


def _measured_bandwidths(strips, per_strip):
    # the lesson's stand-in: build the block and count (a measurement, not a prediction)
    from orientviz.bundle.reduced import geometric_orderings
    from orientviz.bundle.sparsity import bandwidth, reduced_pattern

    blk = ov.simulate_block(strips, per_strip, rng=12, extra=None).block
    fixed = np.all(np.nan_to_num(blk.points.sigma, nan=1.0) == 0.0, axis=1)
    col = np.full(blk.n_points, -1)
    col[~fixed] = np.arange(int(np.sum(~fixed)))
    S = reduced_pattern(blk.observations.image, col[blk.observations.point], blk.n_images)
    return bandwidth(S), min(bandwidth(S, o) for o in geometric_orderings(blk.images.X0))


def _schur_step(nb, mode="ok"):
    m, q = nb.n_images, nb.n_points
    Vi = np.linalg.inv(nb.V)
    WVi = np.einsum("aqj,qjk->aqk", nb.W.reshape(6 * m, q, 3), Vi).reshape(6 * m, 3 * q)
    if mode == "W_transposed":
        WVi = nb.W.T @ block_diag(*Vi)  # a shape error inside the student's function
    sign = -1.0 if mode != "plus" else 1.0
    S = block_diag(*nb.U) + sign * WVi @ nb.W.T
    r = nb.bc + sign * WVi @ nb.bp
    dc = np.linalg.solve(S, r)
    coupling = nb.W.T @ dc if mode != "no_coupling" else 0.0
    dp = np.einsum("qjk,qk->qj", Vi, (nb.bp - coupling).reshape(q, 3)).reshape(-1)
    return dc, dp


# ---- your bundle (lesson 10's last section); the same code as the notebook's solution cells
def _ray_partials_fd(X, X0, R, dR, c, h=1e-6):
    """The numeric shortcut: central differences of the projection (angles along dR)."""

    def proj(X, X0, R):
        uvw = np.einsum("nki,nk->ni", R, X - X0)
        return -c[:, None] * uvw[:, :2] / uvw[:, 2:]

    out = []
    for which in ("X0", "ang", "X"):
        J = np.zeros((len(X), 2, 3))
        for k in range(3):
            e = np.zeros_like(X)
            e[:, k] = h
            if which == "X":
                J[:, :, k] = (proj(X + e, X0, R) - proj(X - e, X0, R)) / (2 * h)
            elif which == "X0":
                J[:, :, k] = (proj(X, X0 + e, R) - proj(X, X0 - e, R)) / (2 * h)
            else:
                J[:, :, k] = (proj(X, X0, R + h * dR[k]) - proj(X, X0, R - h * dR[k])) / (2 * h)
        out.append(J)
    return (proj(X, X0, R), *out)


def _ray_partials(X, X0, R, dR, c, mistake=None):
    d = X - X0
    u, v, w = np.einsum("nki,nk->ni", R, d).T  # Rᵀ (X − X0), ray by ray
    uv_w = (np.stack([u, v], 1) / w[:, None])[:, :, None]

    def quotient(duvw):  # ∂(−c u/w, −c v/w) from ∂(u, v, w)
        return -(c / w)[:, None, None] * (duvw[:, :2] - uv_w * duvw[:, 2:3])

    dX = quotient(np.transpose(R, (0, 2, 1)))  # ∂(u, v, w)/∂X = Rᵀ
    dang = quotient(np.stack([np.einsum("nki,nk->ni", dR[a], d) for a in range(3)], 2))
    xy = -(c / w)[:, None] * np.stack([u, v], 1)
    if mistake == "R_not_transposed":
        uvw = np.einsum("nik,nk->ni", R, d)
        xy = -c[:, None] * uvw[:, :2] / uvw[:, 2:]
    if mistake == "no_quotient":
        dX = -(c / w)[:, None, None] * np.transpose(R, (0, 2, 1))[:, :2]
    if mistake == "X0_sign":
        return xy, dX, dang, dX
    return xy, -dX, dang, dX


def _my_bundle(data, X0, angles, xyz, tol=5e-3, max_iter=20, mistake=None):
    X0, angles, xyz = X0.copy(), angles.copy(), xyz.copy()
    m, p, n = len(X0), data.unknown.size, data.image.size
    j = data.col[data.point]  # point unknown of each ray (−1: fixed)
    var = j >= 0
    c, x0, y0 = data.cam
    history = []
    for it in range(max_iter + 1):
        # 1. linearise: residuals and partial derivatives of every ray
        R = ov.matrix_from_opk(angles[:, 0], angles[:, 1], angles[:, 2])[data.image]
        dR = np.stack(matrix_derivatives(angles[:, 0], angles[:, 1], angles[:, 2]))[:, data.image]
        xy, dX0, dang, dX = _ray_partials(xyz[data.point], X0[data.image], R, dR, c)
        lf = data.l - (xy + np.stack([x0, y0], 1))  # observed − computed, (n, 2) mm
        A, P = np.concatenate([dX0, dang], 2), data.p  # (n, 2, 6), weights (n, 2)
        if mistake == "no_weights":
            P = np.ones_like(P)
        # 2. normal equations: U per image, V per point, W between them; control as observations
        U, V = np.zeros((6 * m, 6 * m)), np.zeros((p, 3, 3))
        W, bc, bp = np.zeros((6 * m, 3 * p)), np.zeros(6 * m), np.zeros((p, 3))
        for r in range(n):
            ci = slice(6 * data.image[r], 6 * data.image[r] + 6)
            U[ci, ci] += A[r].T @ (P[r, :, None] * A[r])
            bc[ci] += A[r].T @ (P[r] * lf[r])
            if var[r]:
                V[j[r]] += dX[r].T @ (P[r, :, None] * dX[r])
                W[ci, 3 * j[r] : 3 * j[r] + 3] += A[r].T @ (P[r, :, None] * dX[r])
                bp[j[r]] += dX[r].T @ (P[r] * lf[r])
        d = data.prior - xyz[data.unknown]  # weighted control coordinates
        if mistake != "no_control":
            V[:, [0, 1, 2], [0, 1, 2]] += data.prior_w
            bp += data.prior_w * d
        vtpv = float(np.sum(P * lf**2) + np.sum(data.prior_w * d**2))
        if it == max_iter or (history and history[-1][1] < tol):
            break
        # 3. reduce to the orientations (Schur), solve, back-substitute point by point
        Vi = np.linalg.inv(V)
        WVi = np.einsum("akj,kji->aki", W.reshape(6 * m, p, 3), Vi).reshape(6 * m, 3 * p)
        dc = np.linalg.solve(U - WVi @ W.T, bc - WVi @ bp.ravel())
        dp = np.einsum("kij,kj->ki", Vi, bp - (W.T @ dc).reshape(p, 3))
        # 4. update; stop when every correction is below tol of its conditional σ
        X0 += dc.reshape(m, 6)[:, :3]
        angles += dc.reshape(m, 6)[:, 3:]
        xyz[data.unknown] += dp
        largest = max(
            np.max(np.abs(dc) * np.sqrt(np.diag(U))),
            np.max(np.abs(dp) * np.sqrt(np.diagonal(V, axis1=1, axis2=2)), initial=0.0),
        )
        history.append((vtpv, largest))
    r = 2 * n + int(np.count_nonzero(data.prior_w)) - 6 * m - 3 * p  # the redundancy
    if mistake == "control_not_counted":
        r -= int(np.count_nonzero(data.prior_w))
    if mistake == "fixed_as_unknowns":
        r -= 3 * int(np.sum(data.col < 0))
    s0 = vtpv / r if mistake == "no_sqrt" else np.sqrt(vtpv / r)
    return X0, angles, xyz, s0, history, (U, W, V)


def _library_bundle(data, X0, angles, xyz):
    """A student who lets the reference path linearise (the lesson's stand-in's pieces)."""
    from orientviz.bundle.reference import linearise

    linearise(data, X0, angles, xyz, data.ap0)  # the call the check must see
    return _my_bundle(data, X0, angles, xyz)


def _point_covariance(U, W, V, j, mistake=None):
    m, p = U.shape[0] // 6, len(V)
    Vi = np.linalg.inv(V)
    if mistake == "V_only":
        return Vi[j]
    WVi = np.einsum("akj,kji->aki", W.reshape(6 * m, p, 3), Vi).reshape(6 * m, 3 * p)
    S = U - WVi @ W.T
    T = W[:, 3 * j : 3 * j + 3] @ Vi[j]
    if mistake == "minus":
        return Vi[j] - T.T @ np.linalg.solve(S, T)
    return Vi[j] + T.T @ np.linalg.solve(S, T)


def _dense_covariance(U, W, V, j):
    """The lesson's stand-in: the whole N inverted (refused: small_matrices)."""
    from scipy.linalg import block_diag

    N = np.block([[U, W], [W.T, block_diag(*V)]])
    k = U.shape[0] + 3 * j
    return np.linalg.inv(N)[k : k + 3, k : k + 3]


def _dense_step(nb):
    """The whole system built from the blocks and solved at once (refused)."""
    from scipy.linalg import block_diag

    N = np.block([[block_diag(*nb.U), nb.W], [nb.W.T, block_diag(*nb.V)]])
    x = np.linalg.solve(N, np.r_[nb.bc, nb.bp])
    return x[: 6 * nb.n_images], x[6 * nb.n_images :]


def _schur_whole_V(nb):
    """The Schur step with the whole V inverted at once (refused)."""
    from scipy.linalg import block_diag

    Vi = np.linalg.inv(block_diag(*nb.V))
    S = block_diag(*nb.U) - nb.W @ Vi @ nb.W.T
    dc = np.linalg.solve(S, nb.bc - nb.W @ Vi @ nb.bp)
    return dc, Vi @ (nb.bp - nb.W.T @ dc)


SOLUTIONS = {
    "check_ray_partials": _ray_partials,
    "check_my_bundle": _my_bundle,
    "check_point_covariance": _point_covariance,
    "check_schur_step": _schur_step,
    "check_coupled": _coupled,
    "check_fill_pattern": _fill_pattern,
    "check_predicted_bandwidth": _predicted_bandwidth,
}

MUTANTS = {
    "check_ray_partials": {
        k: (lambda *a, k=k: _ray_partials(*a, mistake=k))
        for k in ("R_not_transposed", "no_quotient", "X0_sign")
    }
    | {"own central differences": _ray_partials_fd},
    "check_my_bundle": {
        k: (lambda *a, k=k: _my_bundle(*a, mistake=k))
        for k in ("no_weights", "fixed_as_unknowns", "no_sqrt", "no_control", "control_not_counted")
    }
    | {
        "one_step": lambda *a: _my_bundle(*a, max_iter=1),
        "library": _library_bundle,
    },
    "check_point_covariance": {
        k: (lambda U, W, V, j, k=k: _point_covariance(U, W, V, j, k)) for k in ("V_only", "minus")
    }
    | {"the whole N inverted": _dense_covariance},
    "check_schur_step": {
        "the whole system solved densely": _dense_step,
        "the whole V inverted": _schur_whole_V,
        "plus": lambda nb: _schur_step(nb, "plus"),
        "no_coupling": lambda nb: _schur_step(nb, "no_coupling"),
        "W_transposed": lambda nb: _schur_step(nb, "W_transposed"),
    },
    "check_coupled": {
        k: (lambda i, p, m, k=k: _coupled(i, p, m, k))
        for k in (
            "no diagonal",
            "fixed",
            "one triangle",
            "diagonal only where an unknown point is seen",
        )
    },
    "check_fill_pattern": {
        k: (lambda P, k=k: _fill_pattern(P, k)) for k in ("no fill", "envelope")
    },
    "check_predicted_bandwidth": {
        **{
            k: (lambda s, n, k=k: _predicted_bandwidth(s, n, k))
            for k in ("same_direction", "across_2s", "swapped")
        },
        "the stand-in (measured)": _measured_bandwidths,
    },
}
