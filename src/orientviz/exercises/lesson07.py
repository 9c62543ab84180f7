"""Checkers for lesson 07, absolute orientation (3D similarity, X = T + m R x).

Oracles (never :mod:`orientviz.orientation.absolute`):

* error-free simulated truth (the transformation that made the control);
* :func:`scipy.optimize.least_squares` over (T, rotation vector, m) with the checker's own
  Rodrigues rotation, for noisy control;
* central differences of the checker's own model for the design matrix;
* the inverse of a numerically differentiated normal matrix for the precision.

Units: control in m, model coordinates in model units, scale m dimensionless, angles rad.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from ..orientation.absolute import (  # forbidden inside the student's functions, no oracle
    similarity_closed_form,
    similarity_transform,
)
from ._common import (
    CheckFailed,
    call,
    compare,
    complex_step,
    exact_derivatives,
    own_work,
    rng_for,
    success,
)
from ._standin import student_function
from .lesson02 import _axis_rotation

__all__ = [
    "check_design",
    "check_free_axis",
    "check_model_coordinates",
    "check_similarity",
]

F64 = NDArray[np.float64]


def _rotvec(a: F64) -> F64:
    n = float(np.linalg.norm(a))
    return np.eye(3) if n == 0.0 else _axis_rotation(a / n, n)


def _model(rng: np.random.Generator, n: int = 6) -> tuple[F64, float, F64, F64]:
    """Model points (model mm, with relief), and a true scale, rotation, translation."""
    x = np.column_stack(
        [rng.uniform(-100, 100, n), rng.uniform(-100, 100, n), rng.uniform(-8, 8, n)]
    ) + [20.0, -15.0, 30.0]
    m = rng.uniform(8, 12)
    R = _rotvec(rng.normal(0, 0.6, 3))
    T = np.array([512_000.0, 5_402_000.0, 600.0]) + rng.uniform(-500, 500, 3)
    return x, m, R, T


def _unpack(out: object, what: str) -> tuple[float, F64, F64]:
    try:
        m, R, T = out  # type: ignore[misc]
        return float(m), np.asarray(R, dtype=float), np.asarray(T, dtype=float)
    except (TypeError, ValueError):
        raise CheckFailed(f"{what}: expected (m, R, T), got {type(out).__name__}") from None


@own_work(similarity_closed_form=similarity_closed_form, similarity_transform=similarity_transform)
def check_similarity(similarity_svd: Callable[[F64, F64], tuple[float, F64, F64]]) -> None:
    """``similarity_svd(x, X)`` must return (m, R, T) with X ≈ T + m R x (least squares, equal weights)."""
    rng = rng_for("lesson07.check_similarity")
    x, m, R, T = _model(rng)
    X = T + m * x @ R.T
    # 1. error-free control: the truth
    gm, gR, gT = _unpack(
        call(similarity_svd, x.copy(), X.copy(), what="similarity_svd"), "similarity_svd"
    )
    compare(
        "R (error-free control)",
        gR,
        R,
        rtol=1e-9,
        wrong=[("this is Rᵀ: R = V Uᵀ turns model into object vectors", R.T)],
    )
    compare("m (error-free control)", gm, m, rtol=1e-9)
    compare(
        "T (error-free control) [m]",
        gT,
        T,
        rtol=1e-9,
        scale=1000.0,
        wrong=[("T = X̄ − m R x̄: the scale m is missing", T + (m - 1) * R @ x.mean(0))],
    )
    # 2. noisy control: the least-squares optimum
    Xn = X + rng.normal(0, 10.0, X.shape)  # large noise: the symmetric scale then differs clearly

    off = np.round(
        Xn[0]
    )  # the minimiser works near the origin (5·10⁶ m coordinates spoil its steps)

    def resid(q: F64) -> F64:
        return (q[:3] + q[6] * x @ _rotvec(q[3:6]).T - (Xn - off)).ravel()

    ref = np.r_[T - off, _rotvec_of(R), m]
    for _ in range(2):
        ref = least_squares(resid, ref, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15).x
    ref[:3] += off
    xc, Xc = x - x.mean(0), Xn - Xn.mean(0)
    sym = float(np.sqrt((Xc**2).sum() / (xc**2).sum()))
    gm, gR, gT = _unpack(
        call(similarity_svd, x.copy(), Xn.copy(), what="similarity_svd"), "similarity_svd"
    )
    compare(
        "m (noisy control)",
        gm,
        ref[6],
        rtol=1e-8,
        wrong=[
            (
                "this is the symmetric scale √(Σ|X̃|²/Σ|x̃|²), not the least-squares one tr(SD)/Σ|x̃|²",
                sym,
            )
        ],
    )
    compare("R (noisy control)", gR, _rotvec(ref[3:6]), rtol=1e-7)
    compare("T (noisy control) [m]", gT, ref[:3], rtol=1e-7, scale=1000.0)
    # 3. a mirrored model: the best *rotation* must still have det +1
    Xm = X * [1, 1, -1] + rng.normal(0, 0.5, X.shape)
    gm, gR, gT = _unpack(
        call(similarity_svd, x.copy(), Xm, what="similarity_svd"), "similarity_svd"
    )
    det = float(np.linalg.det(gR))
    if abs(det - 1.0) > 1e-9:
        raise CheckFailed(
            f"R for a mirrored model has det {det:+.3f}: fix the sign with D = diag(1, 1, det(V Uᵀ))",
            error=abs(det - 1.0),
            tolerance=1e-9,
        )
    success("similarity from the SVD: the truth, the least-squares optimum, and det R = +1")


def _rotvec_of(R: F64) -> F64:
    """Rotation vector of R (for the oracle's start value only)."""
    angle = np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1))
    if angle < 1e-12:
        return np.zeros(3)
    axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]]) / (2 * np.sin(angle))
    return axis * angle


def check_model_coordinates(to_model: Callable[[F64, float, F64, F64], F64]) -> None:
    """``to_model(X, m, R, T)`` must return the model coordinates x (n, 3) of object points X."""
    rng = rng_for("lesson07.check_model_coordinates")
    x, m, R, T = _model(rng, 5)
    X = T + m * x @ R.T
    got = call(to_model, X.copy(), m, R.copy(), T.copy(), what="to_model")
    wrong = [
        ("turn back with Rᵀ, not R", ((X - T) @ R.T) / m),
        ("divide by m, do not multiply", m * (X - T) @ R),
        ("subtract T first", (X @ R) / m),
    ]
    compare("model coordinates", got, x, rtol=1e-9, wrong=wrong)
    success("model coordinates x = Rᵀ (X − T) / m")


def _numeric_design(x: F64, m: float, R: F64, h: float = 1e-6) -> F64:
    def f(q: F64) -> F64:
        return (q[:3] + q[6] * x @ (_rotvec(q[3:6]) @ R).T).ravel()

    q0 = np.r_[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, m]
    return np.column_stack([(f(q0 + e) - f(q0 - e)) / (2 * h) for e in np.eye(7) * h])


def check_design(design: Callable[[F64, float, F64], F64]) -> None:
    """``design(x, m, R)`` must return ∂X/∂(T, α, m), shape (3n, 7), rows X1, Y1, Z1, X2, …

    α is a small extra rotation about the object axes: X = T + m R(α) R x.
    """
    rng = rng_for("lesson07.check_design")
    x, m, R, _ = _model(rng, 4)
    truth = _numeric_design(x, m, R)
    got = call(design, x.copy(), m, R.copy(), what="design")
    flip = truth.copy()
    flip[:, 3:6] *= -1
    nom = truth.copy()
    nom[:, 3:6] /= m
    model_axes = truth.copy()
    for i, xi in enumerate(x):
        K = np.array([[0, -xi[2], xi[1]], [xi[2], 0, -xi[0]], [-xi[1], xi[0], 0]])
        model_axes[3 * i : 3 * i + 3, 3:6] = -m * R @ K
    wrong = [
        ("the rotation columns have the wrong sign: d(Rx) = α × Rx = −[Rx]ₓ α", flip),
        ("the rotation columns need the scale m", nom),
        ("the scale column is ∂X/∂m = R x, without m", truth * np.r_[1, 1, 1, 1, 1, 1, m]),
        (
            "these are the partials of a rotation about the MODEL axes, X = T + m R R(α) x "
            "(−m R [x]ₓ); α turns about the object axes, X = T + m R(α) R x: −m [R x]ₓ",
            model_axes,
        ),
    ]
    compare("design matrix", got, truth, rtol=1e-6, wrong=wrong)

    def similarity(q: F64) -> F64:  # X = T + m R(α) R x with R(α) ≈ I + K + K²/2 (tiny complex α)
        a = q[3:6]
        K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
        return (q[:3] + q[6] * x @ ((np.eye(3) + K + K @ K / 2) @ R).T).ravel()

    exact = complex_step(similarity, np.r_[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, m])
    exact_derivatives("design matrix", got, exact)
    success(
        "design matrix of the similarity agrees with numerical derivatives and, to "
        "round-off, with exact ones"
    )


def check_free_axis(free_axis: Callable[[F64], F64]) -> None:
    """``free_axis(x_control)`` must return the unit vector (model frame, either sign) about
    which a model can still turn when all its full control points lie on one straight line.

    Oracle: the null vector of the numerically differentiated similarity at those points
    (rank 6 of 7); its rotation part, turned into the model frame.
    """
    rng = rng_for("lesson07.check_free_axis")
    for case, n in enumerate((3, 5, 4)):
        x, m, R, _ = _model(rng, n)
        u = rng.normal(0.0, 1.0, 3)
        u /= np.linalg.norm(u)
        base = x[0] + rng.uniform(-30.0, 30.0, 3)
        x_ctl = base + np.outer(rng.uniform(-120.0, 120.0, n), u)  # a road: one straight line
        null = np.linalg.svd(_numeric_design(x_ctl, m, R))[2][-1]
        axis = R.T @ null[3:6]
        axis /= np.linalg.norm(axis)
        got = np.asarray(call(free_axis, x_ctl.copy(), what="free_axis"), dtype=float)
        if got.shape != (3,):
            raise CheckFailed(f"free_axis: expected a vector of 3 numbers, got shape {got.shape}")
        if float(got @ axis) < 0.0:
            got = -got  # the sign of the axis is free
        centroid = x_ctl.mean(axis=0) / np.linalg.norm(x_ctl.mean(axis=0))
        size = float(np.linalg.norm(got))
        wrong = [
            ("return a UNIT vector: divide by its length", axis * size),
            ("this is the direction from the model origin to the control's centroid; the "
             "origin plays no part — the free rotation turns about the line of the points",
             centroid * np.sign(float(centroid @ axis) or 1.0)),
        ]  # fmt: skip
        if size > 0 and abs(float(got @ axis)) < 0.1 * size:
            wrong.append(("this is perpendicular to the line of the control points (a smallest "
                          "singular vector of the centred points?): the rotation they cannot "
                          "fix turns about the line itself", got))  # fmt: skip
        compare(f"free axis of control on one line (case {case + 1}, {n} points)", got, axis,
                rtol=1e-6, scale=1.0, wrong=wrong)  # fmt: skip
    success("the rotation that control on one line cannot fix turns about that line (3 cases)")


def _partial_control(rng: np.random.Generator):
    """A model with full, planimetric and height control points, unequal σ, and a poor start."""
    x, m, R, T = _model(rng, 8)
    sigma = np.tile([0.05, 0.05, 0.03], (8, 1)) * rng.uniform(0.5, 2.0, (8, 1))
    X = T + m * x @ R.T + rng.normal(0.0, 1.0, x.shape) * sigma
    observed = np.ones((8, 3), bool)
    observed[[1, 5], 2] = False  # planimetric control
    observed[[2, 6], :2] = False  # height control
    start = (m * 1.02, _rotvec(np.array([0.02, -0.015, 0.03])) @ R, T + [3.0, -2.0, 1.5])
    return x, X, sigma, observed, start, (m, R, T)


def _gn_oracle(x, X, sigma, observed):
    """The weighted least-squares similarity by scipy's minimiser (near the origin)."""
    off = np.round(X[0])
    w = observed / sigma

    def resid(q: F64) -> F64:
        return (w * (q[:3] + q[6] * x @ _rotvec(q[3:6]).T - (X - off))).ravel()

    xc, Xc = x - x.mean(0), X - X.mean(0)
    U, S, Vt = np.linalg.svd(xc.T @ Xc)
    R0 = Vt.T @ np.diag([1, 1, np.linalg.det(Vt.T @ U.T)]) @ U.T
    m0 = float(np.sqrt((Xc**2).sum() / (xc**2).sum()))
    q = np.r_[X.mean(0) - m0 * R0 @ x.mean(0) - off, _rotvec_of(R0), m0]
    for _ in range(3):
        q = least_squares(resid, q, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15).x
    v = resid(q)[observed.ravel()]
    return q[6], _rotvec(q[3:6]), q[:3] + off, float(np.sqrt(v @ v / (observed.sum() - 7)))


def _rotation_on_wrong_side(fn: Callable, rng: np.random.Generator) -> bool:
    """Does one step of ``fn`` apply the rotation correction on the wrong side (R ← R R(α))?

    Error-free control, the start off in R only, by 0.01 rad about an oblique axis: one
    Gauss-Newton step with R ← R(α) R leaves an error of second order (~1e-4 rad); with
    R ← R R(α) the correction turns about the wrong axes and the error stays of first order.
    """
    x, m, R, T = _model(rng, 6)
    X = T + m * x @ R.T
    start = (m, _rotvec(np.array([0.006, -0.005, 0.006])) @ R, T.copy())
    try:
        out = fn(x.copy(), X, np.ones_like(X), np.ones(X.shape, bool),
                 (start[0], start[1].copy(), start[2].copy()), 1e-10, 1)  # tol, max_iter = 1  # fmt: skip
        R1 = np.asarray(out[1], float)
        err = np.arccos(np.clip((np.trace(R1 @ R.T) - 1.0) / 2.0, -1.0, 1.0))
    except Exception:  # noqa: BLE001 - a probe only: any failure means "cannot tell"
        return False
    return bool(err > 3e-3)


@own_work(similarity_transform=similarity_transform)
def check_similarity_gn(fn: Callable) -> None:
    """``fn(x, X, sigma, observed, start) -> (m, R, T, sigma0)``: the weighted least-squares
    similarity X ≈ T + m R x by Gauss-Newton from ``start = (m, R, T)``, using only the control
    coordinates marked in ``observed`` (n, 3) with their σ (n, 3) m; σ̂0 with r = n_obs − 7."""
    rng = rng_for("lesson07.check_similarity_gn")
    x, X, sigma, observed, start, _ = _partial_control(rng)
    got = call(fn, x.copy(), X.copy(), sigma.copy(), observed.copy(),
               (start[0], start[1].copy(), start[2].copy()), what="similarity_gn")  # fmt: skip
    if not isinstance(got, tuple) or len(got) != 4:
        raise CheckFailed("similarity_gn: return (m, R, T, sigma0)")
    m, R, T, s0 = got
    wm, wR, wT, ws0 = _gn_oracle(x, X, sigma, observed)
    wrong_m = [
        ("the weights are missing: each control coordinate counts with 1/σ² (σ differ here)",
         _gn_oracle(x, X, np.ones_like(sigma), observed)[0]),
    ]  # fmt: skip
    try:
        compare("m", float(m), wm, rtol=1e-8, wrong=wrong_m)
    except CheckFailed as exc:
        if "weights" not in str(exc) and abs(float(m) - wm) < 0.1 * abs(start[0] - wm):
            raise CheckFailed(
                f"{exc}\n  (much closer than the start, but not there: iterate until every "
                "correction is tiny — one Gauss-Newton step is not the adjustment)",
                exc.error, exc.tolerance,
            ) from None  # fmt: skip
        raise
    try:
        compare("R", np.asarray(R, float), wR, rtol=1e-7, wrong=[
            ("this is Rᵀ: R turns model into object vectors", wR.T),
        ])  # fmt: skip
    except CheckFailed as exc:
        if "Rᵀ" not in str(exc) and _rotation_on_wrong_side(student_function(fn), rng):
            raise CheckFailed(
                f"{str(exc).splitlines()[0]} — the rotation correction is applied on the wrong "
                "side: α is a small rotation about the OBJECT axes (the design's columns), so "
                "R ← R(α) R, not R R(α) (one step from a start off in R only leaves a first-order "
                "error)", exc.error, exc.tolerance,
            ) from None  # fmt: skip
        raise
    compare("T [m]", np.asarray(T, float), wT, rtol=1e-7, scale=1000.0)
    n_obs = int(observed.sum())
    compare("σ̂0", float(s0), ws0, rtol=1e-7, wrong=[
        (f"the redundancy is the number of control coordinates ({n_obs}) − 7, not {n_obs}",
         ws0 * np.sqrt((n_obs - 7) / n_obs)),
        ("the square root is missing", ws0**2),
    ])  # fmt: skip
    success(
        f"m, R, T and σ̂0 = {ws0:.3f} of partial control ({n_obs} coordinates) as scipy's minimiser finds them"
    )
