"""Checkers for lesson 08's own block method: the independent-model adjustment.

Two exercises: the partial derivatives of one model point's similarity λ R m + T by the
seven parameters (a rotation increment θ with R ← R exp([θ]×), λ, T), and the whole
Gauss-Newton adjustment of all models and tie points of a block with fixed control.

Oracles: central differences of the checker's own similarity (Rodrigues' formula written
out here) for the partial derivatives; for the adjustment the library's rigorous
:func:`~orientviz.stereo_models.independent_models` on a small block the check simulates
itself (never the lesson's), and the weighted sum vᵀPv of the answer, computed here, to tell
a solution that has not reached the minimum from one that minimises something else.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from ..rotation import matrix_from_opk
from ..simulate import simulate_block
from ..stereo_models import form_models, independent_models, solve_rows, tie_setup
from ._common import CheckFailed, call, compare, complex_step, exact_derivatives, own_work, success

F64 = NDArray[np.float64]

__all__ = ["check_model_jacobian", "check_adjust_models", "model_jacobian_numeric"]


def _cross(v: F64) -> F64:
    """[v]× for rows v (k, 3) → (k, 3, 3), written out."""
    out = np.zeros(v.shape[:-1] + (3, 3), dtype=np.result_type(v, float))
    out[..., 0, 1], out[..., 0, 2], out[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    out[..., 1, 0], out[..., 2, 0], out[..., 2, 1] = v[..., 2], -v[..., 1], v[..., 0]
    return out


def _expm(theta: F64) -> F64:
    """exp([θ]×) for rows θ (k, 3) by Rodrigues' formula (small angles included)."""
    a = np.linalg.norm(theta, axis=-1)[..., None, None]
    K = _cross(theta)
    small = a < 1e-12
    s = np.where(small, 1.0, np.sin(a) / np.where(small, 1.0, a))
    c = np.where(small, 0.5, (1 - np.cos(a)) / np.where(small, 1.0, a) ** 2)
    return np.eye(3) + s * K + c * K @ K


def _similarity(p: F64, R: F64, m: F64) -> F64:
    """λ R exp([θ]×) m + T for parameters p (k, 7) = (θ1, θ2, θ3, λ, T_X, T_Y, T_Z)."""
    Rt = R @ _expm(p[:, :3])
    return p[:, 3, None] * np.einsum("kij,kj->ki", Rt, m) + p[:, 4:]


def model_jacobian_numeric(lam: F64, R: F64, m: F64) -> F64:
    """Partials of λ R exp([θ]×) m + T at θ = 0 by central differences, (k, 3, 7).

    Lesson 08's stand-in while the student's ``model_jacobian`` is a blank (its check
    refuses it: the exercise is the derivation).

    Parameters
    ----------
    lam : ndarray, shape (k,)
        Scale of each row's model.
    R : ndarray, shape (k, 3, 3)
        Rotation of each row's model (model → object).
    m : ndarray, shape (k, 3)
        Model coordinates in m.

    Returns
    -------
    ndarray, shape (k, 3, 7)
        Columns θ1, θ2, θ3 (m/rad), λ (m), T_X, T_Y, T_Z (–).
    """
    lam, R, m = np.asarray(lam, float), np.asarray(R, float), np.asarray(m, float)
    p0 = np.zeros((len(m), 7))
    p0[:, 3] = lam
    J = np.zeros((len(m), 3, 7))
    for c in range(7):
        h = 1e-6 * max(1.0, float(np.max(np.abs(p0[:, c]))))
        e = np.zeros(7)
        e[c] = h
        J[:, :, c] = (_similarity(p0 + e, R, m) - _similarity(p0 - e, R, m)) / (2 * h)
    return J


@own_work(
    "the exercise is the derivation; central differences (the stand-in above) skip it",
    model_jacobian_numeric=model_jacobian_numeric,
)
def check_model_jacobian(fn: Callable) -> None:
    """Check ``fn(lam, R, m) -> J`` (k, 3, 7): ∂(λ R exp([θ]×) m + T)/∂(θ, λ, T) at θ = 0."""
    rng = np.random.default_rng(8081)
    k = 5
    lam = rng.uniform(0.8, 9.5, k)
    R = _expm(rng.normal(0.0, 0.9, (k, 3)))
    m = rng.uniform(-120.0, 120.0, (k, 3)) + [0.0, 0.0, -150.0]
    got = call(fn, lam.copy(), R.copy(), m.copy(), what="model_jacobian")
    want = model_jacobian_numeric(lam, R, m)
    Rm = np.einsum("kij,kj->ki", R, m)
    wrong_rot = {
        "the rotation columns have the wrong sign: ∂(R exp([θ]×) m)/∂θ = R [θ]× m / θ "
        "= −R [m]× (because θ × m = −m × θ)": lam[:, None, None] * (R @ _cross(m)),
        "these are the partials of the increment on the left, R ← exp([θ]×) R (−λ [R m]×); "
        "the update here is R ← R exp([θ]×), so the rotation acts on m first: −λ R [m]×":
            -lam[:, None, None] * _cross(Rm),
        "the rotation columns lack the scale λ: −λ R [m]×": -(R @ _cross(m)),
        "the rotation columns lack R: the increment turns m in the model frame, then R "
        "turns it into the object frame: −λ R [m]×": -lam[:, None, None] * _cross(m),
    }  # fmt: skip
    wrong = []
    for text, rot in wrong_rot.items():
        w = want.copy()
        w[:, :, :3] = rot
        wrong.append((text, w))
    w = want.copy()
    w[:, :, 3] = m
    wrong.append(("the λ column is R m (the model point turned into the object frame), not m", w))
    compare(
        "∂(λ R exp([θ]×) m + T)/∂(θ, λ, T) of five points, (5, 3, 7)",
        got, want, rtol=1e-6, scale=float(np.max(np.abs(want))), wrong=wrong,
    )  # fmt: skip

    def similarity(p: np.ndarray) -> np.ndarray:  # p (k, 7): θ, a change of λ, T; complex
        K = _cross(p[:, :3])
        E = np.eye(3) + K + K @ K / 2.0  # exp([θ]×) for the complex step's tiny θ
        return (lam + p[:, 3])[:, None] * np.einsum("kij,kjl,kl->ki", R, E, m) + p[:, 4:]

    exact = np.einsum("iaij->iaj", complex_step(similarity, np.zeros((k, 7))))
    exact_derivatives("∂(λ R exp([θ]×) m + T)/∂(θ, λ, T)", got, exact)
    success(
        "the partials of λ R exp([θ]×) m + T agree with central differences of the similarity"
        " and, to round-off, with its complex-step derivatives"
    )


def _check_block(rng: np.random.Generator):
    """A small block (2 strips × 5 images) with one control point turned into a height point."""
    sim = simulate_block(2, 5, rng=rng, extra=None, control="perimeter", control_spacing=2)
    block = sim.block.copy()
    ms = form_models(block)
    su = tie_setup(block, ms)
    ctrl = su.tie_points[~np.isnan(su.known[: su.tie_points.size, 0])]
    block.points.xyz_known[ctrl[len(ctrl) // 2], :2] = np.nan  # X, Y unknown, Z given
    return block, ms


def _inputs(block, ms, sigma: F64):
    su = tie_setup(block, ms)
    su.init_points(np.ones(ms.n_models), ms.start_rotation, ms.start_translation)
    free = su.scalar >= 0
    return su, (su.m.copy(), su.row_model.copy(), su.row_point.copy(), su.X.copy(), free,
                sigma.copy(), ms.start_rotation.copy(), ms.start_translation.copy())  # fmt: skip


def _library(block, ms, su, sigma: F64):
    """The library's rigorous adjustment: (λ, R, T, X of the tie table, σ̂0)."""
    res = independent_models(block, models=ms, sigma_model=(float(sigma[0]), float(sigma[2])))
    p = res.x[: 7 * ms.n_models].reshape(-1, 7)
    X = np.vstack([res.points[su.tie_points], res.centres[su.centre_images]])
    return p[:, 6], matrix_from_opk(*p[:, 3:6].T), p[:, :3], X, res.sigma0


def _unpack(out, n: int, nt: int):
    try:
        lam, R, T, X, s0 = out
        lam, R, T, X = (np.asarray(a, float) for a in (lam, R, T, X))
        s0 = float(s0)
    except (TypeError, ValueError):
        raise CheckFailed("adjust_models: return the five values (lam, R, T, X, sigma0)") from None
    want = {"lam": (n,), "R": (n, 3, 3), "T": (n, 3), "X": (nt, 3)}
    for name, a in zip(want, (lam, R, T, X)):
        if a.shape != want[name]:
            raise CheckFailed(f"adjust_models: {name} must have shape {want[name]}, got {a.shape}")
    return lam, R, T, X, s0


@own_work(
    "the exercise is the adjustment itself; the library's independent_models (the stand-in "
    "above) is what yours is compared with",
    independent_models=independent_models,
    solve_rows=solve_rows,
)
def check_adjust_models(fn: Callable) -> None:
    """Check ``fn(m, model, point, X, free, sigma, R, T) -> (lam, R, T, X, sigma0)``.

    The independent-model adjustment of a block the check simulates (2 strips × 5 images,
    one control point with Z only) against the library's rigorous solution: tie points and
    projection centres within 1 % of σ_xy, λ within 1e-6, R within 1e-6 rad, T within 1 % of
    σ_xy, σ̂0 within 0.1 %.
    """
    rng = np.random.default_rng(8082)
    block, ms = _check_block(rng)
    sigma = np.array([0.03, 0.03, 0.21])  # m: σ_Z seven times σ_XY
    su, args = _inputs(block, ms, sigma)
    X_start, free = args[3], args[4]
    out = call(fn, *args, what="adjust_models")
    lam, R, T, X, s0 = _unpack(out, ms.n_models, su.X.shape[0])
    if not np.allclose(X[~free], X_start[~free], rtol=0.0, atol=1e-9):
        raise CheckFailed(
            "adjust_models: the given control coordinates moved; they are fixed (not unknowns). "
            "A point with Z only keeps X, Y free and Z fixed: decide per coordinate (`free`)."
        )
    lam_l, R_l, T_l, X_l, s0_l = _library(block, ms, su, sigma)
    w = 1.0 / sigma**2

    def cost(lam_, R_, T_, X_) -> float:
        j = su.row_model
        v = lam_[j, None] * np.einsum("kij,kj->ki", R_[j], su.m) + T_[j] - X_[su.row_point]
        return float(np.sum(v**2 * w))

    err = float(np.max(np.abs(X - X_l))) / sigma[0]
    if not np.isfinite(err) or err > 0.01:
        _, _, _, X_u, _ = _library(block, ms, su, np.full(3, sigma[0]))
        if np.max(np.abs(X - X_u)) < 0.01 * sigma[0]:
            why = ("it is the adjustment with equal weights: weight each coordinate by 1/σ² "
                   f"(σ_Z = {sigma[2]} m is seven times σ_X, σ_Y here)")  # fmt: skip
        elif np.isfinite(err) and cost(lam, R, T, X) > cost(lam_l, R_l, T_l, X_l) * (1 + 1e-6):
            why = (f"vᵀPv of your result is {cost(lam, R, T, X):.6g}, the minimum is "
                   f"{cost(lam_l, R_l, T_l, X_l):.6g}: not converged — iterate until the "
                   "corrections are small; if it does not settle, check the signs of the "
                   "partials, the side of the update R ← R exp([θ]×) and v = λRm + T − X")  # fmt: skip
        else:
            why = "compare your design matrix with the derived partials (one row block per point)"
        raise CheckFailed(
            f"adjust_models: the tie points differ from the library's by up to {err:.3g} σ_xy "
            f"(allowed 0.01): {why}",
            error=err if np.isfinite(err) else np.inf,
            tolerance=0.01,
        )
    compare("the models' scales λ", lam, lam_l, rtol=1e-6)

    # the rotations: angle of R_libᵀ R per model; a transposed R is named
    def angles(R_: F64) -> F64:
        c = (np.einsum("kji,kji->k", R_l, R_) - 1.0) / 2.0  # (trace(R_libᵀ R) − 1) / 2
        return np.arccos(np.clip(c, -1.0, 1.0))

    da = float(np.max(angles(R)))
    if not np.isfinite(da) or da > 1e-6:
        if np.max(angles(np.transpose(R, (0, 2, 1)))) < 1e-6:
            why = "R is returned transposed: the model rotation takes model to object coordinates"
        elif np.max(np.abs(R - args[6])) < 1e-12:
            why = "these are the start rotations: return the adjusted R, not the given one"
        else:
            why = "the rotations do not fit the adjusted points: update R ← R exp([θ]×) each step"
        raise CheckFailed(
            f"adjust_models: the models' rotations differ from the library's by up to {da:.3g} rad "
            f"(allowed 1e-6): {why}",
            error=da if np.isfinite(da) else np.inf,
            tolerance=1e-6,
        )
    compare(
        "the models' translations T [m]",
        T,
        T_l,
        rtol=0.01 * sigma[0],
        scale=1.0,
        wrong=[
            ("these are the start translations: return the adjusted T", args[7]),
            ("T must be returned, not zeros", np.zeros_like(T_l)),
        ],
    )
    n_obs, n_unknown = 3 * su.row_model.size, 7 * ms.n_models + int(free.sum())
    r = n_obs - n_unknown
    s = s0_l * np.sqrt(r)  # √(vᵀPv)
    compare(
        "σ̂0",
        s0,
        s0_l,
        rtol=1e-3,
        wrong=[
            (f"the redundancy lacks the {int(free.sum())} coordinate unknowns: "
             "r = 3·rows − 7·models − free coordinates", s / np.sqrt(n_obs - 7 * ms.n_models)),
            (f"the redundancy lacks the 7·{ms.n_models} model parameters",
             s / np.sqrt(n_obs - int(free.sum()))),
            ("divided by the number of observations, not by the redundancy", s / np.sqrt(n_obs)),
            ("this is σ̂0², not σ̂0", s0_l**2),
        ],
    )  # fmt: skip
    success(
        f"{ms.n_models} models, {su.X.shape[0]} tie points and centres agree with the "
        f"library's independent models within {err:.1e} σ_xy; σ̂0 {s0:.4f} (library {s0_l:.4f})"
    )
