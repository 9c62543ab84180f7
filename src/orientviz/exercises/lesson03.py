"""Checkers for lesson 03 (DLT and interior orientation).

Oracles: error-free simulated images of a 3-D test field with a known camera (X0, R, c,
x0, y0); the true DLT parameters are built from them by hand (P = K Rᵀ [I | −X0],
scaled to P[2, 3] = 1), never by the library's estimator.
"""

from __future__ import annotations

import numpy as np

from ..orientation.dlt import dlt, dlt_to_orientation  # forbidden in the derivations (own_work)
from ..orientation.interior import fiducial_transformation  # forbidden in affine_fit
from ..rotation import matrix_from_opk
from ._common import CheckFailed, call, compare, own_work, rng_for, success


def _scene(rng, affine=False):
    """A camera 7 m in front of a 6 × 4 × 2.5 m test field; its true P and image points."""
    X = rng.uniform([-3.0, -2.0, 0.0], [3.0, 2.0, 2.5], (10, 3))
    X0 = np.array([rng.uniform(-1, 1), -7.0 + rng.uniform(-0.5, 0.5), rng.uniform(1.0, 2.0)])
    ang = np.array([1.45 + rng.uniform(-0.1, 0.1), rng.uniform(-0.2, 0.2), rng.uniform(-0.3, 0.3)])
    c, x0, y0 = rng.uniform(20.0, 35.0), rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3)
    R = matrix_from_opk(*ang)
    K = np.array([[-c, 0.0, x0], [0.0, -c, y0], [0.0, 0.0, 1.0]])
    if affine:
        K[1, 1] *= 1.003
        K[0, 1] = 0.002 * K[1, 1]
    P = K @ R.T @ np.hstack([np.eye(3), -X0[:, None]])
    P = P / P[2, 3]
    h = np.column_stack([X, np.ones(len(X))]) @ P.T
    xy = h[:, :2] / h[:, 2:]
    return X, xy, P, X0, (c, x0, y0)


# --------------------------------------------------------------------- moving the origin


def _shifted_wrongly(L, t, how):
    """Wrong answers of shift_origin: no rescaling, the last column only, the shift reversed."""
    P = np.append(np.asarray(L, float), 1.0).reshape(3, 4)
    Q = np.hstack([P[:, :3], P[:, :3] @ (-t if how == "sign" else t)[:, None] + P[:, 3:]])
    if how == "last column":
        Q[:, 3] /= Q[2, 3]
    elif how == "sign":
        Q = Q / Q[2, 3]
    return Q.reshape(-1)[:11]


def check_shift_origin(fn) -> None:
    """``fn(L, t) -> L_new``: the eleven DLT parameters of the same image after the object
    origin is moved to the point ``t`` (old coordinates, m): X_new = X − t, again scaled to
    L12 = 1."""
    for salt in range(3):
        rng = rng_for("lesson03.check_shift_origin", salt)
        X, xy, P, X0, (c, x0, y0) = _scene(rng)
        t = rng.uniform([-2.0, -1.0, 0.0], [2.0, 3.0, 2.0])
        L = P.reshape(-1)[:11]
        # oracle: the camera itself in the new coordinates (projection centre X0 − t), built from
        # (c, x0, y0, R) as in _scene; R from the true P: M = λ K Rᵀ
        K = np.array([[-c, 0.0, x0], [0.0, -c, y0], [0.0, 0.0, 1.0]])
        Rt = np.linalg.solve(K, P[:, :3])
        Q = K @ Rt @ np.hstack([np.eye(3), -(X0 - t)[:, None]])
        want = (Q / Q[2, 3]).reshape(-1)[:11]
        got = call(fn, L.copy(), t.copy(), what="shift_origin")
        compare(f"L after moving the origin (image {salt + 1})", got, want, rtol=1e-9, wrong=[
            ("the new P is not scaled back to L12 = 1: divide all twelve entries by the new "
             "L12 = m3·t + 1", _shifted_wrongly(L, t, "none")),
            ("only the last column is divided by the new L12: the common factor λ scales "
             "all of P, M too", _shifted_wrongly(L, t, "last column")),
            ("the shift goes the wrong way: X = X_new + t, so p4 becomes M t + p4",
             _shifted_wrongly(L, t, "sign")),
        ])  # fmt: skip
    success("the moved DLT parameters agree with the cameras built in the new coordinates "
            "(three images)")  # fmt: skip


# --------------------------------------------------------------------- projection centre


def _viewing_cases(rng):
    """Two cameras looking along +Y at a test field: the object origin in front of the first
    (λ < 0 once P is scaled to L12 = 1), behind the second (λ > 0); their true axes −R e_Z."""
    out = []
    for Y0 in (-7.0, 8.0):
        ang = np.array(
            [1.45 + rng.uniform(-0.1, 0.1), rng.uniform(-0.2, 0.2), rng.uniform(-0.3, 0.3)]
        )
        R = matrix_from_opk(*ang)
        X0 = np.array([rng.uniform(-1, 1), Y0, rng.uniform(1.0, 2.0)])
        c = rng.uniform(20.0, 35.0)
        K = np.array(
            [[-c, 0.0, rng.uniform(-0.3, 0.3)], [0.0, -c, rng.uniform(-0.3, 0.3)], [0, 0, 1.0]]
        )
        P = K @ R.T @ np.hstack([np.eye(3), -X0[:, None]])
        P = P / P[2, 3]
        out.append((P.reshape(-1)[:11], -R[:, 2], P))
    return out


@own_work(
    "the exercise is the derivation from L; the library's decomposition skips it",
    dlt_to_orientation=dlt_to_orientation,
    dlt=dlt,
)
def check_viewing_direction(fn) -> None:
    """``fn(L) -> v``: the unit vector (object frame) along which the camera of the eleven DLT
    parameters looks, from its projection centre towards the scene."""
    cases = _viewing_cases(rng_for("lesson03.check_viewing_direction"))
    got = [
        np.asarray(call(fn, L.copy(), what="viewing_direction"), dtype=float) for L, _, _ in cases
    ]
    views = [view for _, view, _ in cases]
    m3 = [P[2, :3] / np.linalg.norm(P[2, :3]) for _, _, P in cases]

    def same(a: np.ndarray, b: np.ndarray) -> bool:
        return a.shape == b.shape and float(np.abs(a - b).max()) < 1e-6

    if all(same(g, -v) for g, v in zip(got, views)):
        text = ("this points from the scene to the camera: the image plane is at z = −c, so the "
                "camera looks along −r3")  # fmt: skip
    elif all(same(g, m) for g, m in zip(got, m3)) or all(same(g, -m) for g, m in zip(got, m3)):
        text = ("the sign of λ is missing: L is scaled so that L12 = 1, which can turn P round — "
                "M = λKRᵀ, and det M has the sign of λ (det K = c² > 0)")  # fmt: skip
    else:
        text = ""
    for k, (g, v) in enumerate(zip(got, views)):
        compare(f"viewing direction of camera {k + 1}", g, v, rtol=1e-9, scale=1.0,
                wrong=[(text, g)] if text else [])  # fmt: skip
    success("viewing directions of two cameras, one with the object origin in front, one behind")


# --------------------------------------------------------------------- interior orientation


def _interior_unnormalised(L):
    P = np.append(np.asarray(L, float), 1.0).reshape(3, 4)
    m1, m2, m3 = P[0, :3], P[1, :3], P[2, :3]
    x0, y0 = m1 @ m3, m2 @ m3
    return np.array([np.sqrt(m1 @ m1 / (m3 @ m3) - x0 * x0 / (m3 @ m3) ** 2), x0, y0])


def _interior_no_x0(L):
    P = np.append(np.asarray(L, float), 1.0).reshape(3, 4)
    m1, m2, m3 = P[0, :3], P[1, :3], P[2, :3]
    q = m3 @ m3
    return np.array([np.sqrt(m1 @ m1 / q), m1 @ m3 / q, m2 @ m3 / q])


def _interior_swapped(L):
    P = np.append(np.asarray(L, float), 1.0).reshape(3, 4)
    m1, m2, m3 = P[0, :3], P[1, :3], P[2, :3]
    q = m3 @ m3
    x0, y0 = m2 @ m3 / q, m1 @ m3 / q
    return np.array([np.sqrt(m1 @ m1 / q - y0 * y0), x0, y0])


@own_work(
    "the exercise is the derivation from L; the library's decomposition skips it",
    dlt_to_orientation=dlt_to_orientation,
    dlt=dlt,
)
def check_interior_from_dlt(fn) -> None:
    """``fn(L) -> (c, x0, y0)`` in mm from the DLT of a camera with square pixels and no
    shear (then the two affine parameters are zero)."""
    for salt in range(2):
        X, xy, P, X0, io = _scene(rng_for("lesson03.check_interior_from_dlt", salt))
        L = P.reshape(-1)[:11]
        got = np.asarray(call(fn, L.copy(), what="interior_from_dlt"), dtype=float)
        compare("(c, x0, y0) [mm]", got, np.array(io), rtol=1e-9, wrong=[
            ("x0 and y0 need the division by |m3|² (P is scaled so that P[2, 3] = 1, not |m3| = 1)",
             _interior_unnormalised(L)),
            ("|m1|²/|m3|² = c² + x0²: subtract x0² before the square root", _interior_no_x0(L)),
            ("x0 and y0 are swapped: x0 comes from the first row m1", _interior_swapped(L)),
        ])  # fmt: skip
    success("c, x0, y0 agree with the simulated camera (two cameras)")


# --------------------------------------------------------------------- the affine fiducial fit


def _fiducials(rng):
    """Eight fiducials (calibrated, mm), an affine map and the machine coordinates."""
    cal = np.array([[-106.0, 0.0], [106.0, 0.0], [0.0, -106.0], [0.0, 106.0],
                    [-106.0, -106.0], [106.0, 106.0], [-106.0, 106.0], [106.0, -106.0]])  # fmt: skip
    M = np.array([[1.0007, 0.0021], [-0.0018, 0.9989]])
    t = np.array([12.3, -7.9])
    machine = (cal - t) @ np.linalg.inv(M).T  # calibrated = t + M machine
    return machine, cal, np.array([t[0], M[0, 0], M[0, 1], t[1], M[1, 0], M[1, 1]])


@own_work(fiducial_transformation=fiducial_transformation)
def check_affine_fit(fn) -> None:
    """``fn(machine, calibrated) -> (params, v, sigma0)``: x = a0 + a1 ξ + a2 η,
    y = b0 + b1 ξ + b2 η; params (a0, a1, a2, b0, b1, b2), v (2n,) mm in the order x1, y1, …,
    σ̂0 in mm with r = 2n − 6."""
    rng = rng_for("lesson03.check_affine_fit")
    machine, cal, truth = _fiducials(rng)
    got = call(fn, machine.copy(), cal.copy(), what="affine_fit")
    if not isinstance(got, tuple) or len(got) != 3:
        raise CheckFailed("affine_fit: return the three results (params, v, sigma0)")
    compare("params of error-free fiducials", got[0], truth, rtol=1e-9, wrong=[
        ("the order is a0, a1, a2, b0, b1, b2 (x's three, then y's three)", truth[[0, 3, 1, 4, 2, 5]]),
    ])  # fmt: skip
    noisy = cal + rng.normal(0.0, 0.002, cal.shape)
    got = call(fn, machine.copy(), noisy.copy(), what="affine_fit")
    # oracle: x and y are two separate 3-parameter fits (numpy's lstsq)
    D = np.column_stack([np.ones(len(machine)), machine])
    px = np.linalg.lstsq(D, noisy[:, 0], rcond=None)[0]
    py = np.linalg.lstsq(D, noisy[:, 1], rcond=None)[0]
    v = np.column_stack([D @ px - noisy[:, 0], D @ py - noisy[:, 1]]).ravel()
    s0 = float(np.sqrt(v @ v / (v.size - 6)))
    compare("params of noisy fiducials", got[0], np.r_[px, py], rtol=1e-8)
    compare("v [mm]", got[1], v, rtol=1e-6, wrong=[
        ("the sign of v is wrong: v = A x̂ − l (computed − observed)", -v),
        ("v in the order x1, y1, x2, y2, …", np.r_[v[0::2], v[1::2]]),
    ])  # fmt: skip
    compare("σ̂0 [mm]", got[2], s0, rtol=1e-8, wrong=[
        ("the redundancy is 2n − 6 (six parameters), not 2n", np.sqrt(v @ v / v.size)),
        ("the redundancy is 2n − 6 (six parameters), not 2n − 3", np.sqrt(v @ v / (v.size - 3))),
    ])  # fmt: skip
    success(
        f"the affine map of error-free fiducials comes back; σ̂0 = {s0 * 1000:.2f} µm as two lstsq fits give"
    )
