"""Checkers for lesson 05, relative orientation of a dependent pair from y-parallaxes.

Oracles (never :mod:`orientviz.orientation.relative` or :mod:`~orientviz.orientation.schemes`):

* the rigorous y-parallax of a simulated pair, computed here: the right image is taken with
  the true elements (by, bz, ω, φ, κ), both images are put back in the normal case, and
  p_y = Y_left − Y_right is read where the rays meet in the XZ projection;
* the design matrix: central differences of that rigorous parallax at the normal case;
* rays built with a known Y gap (the parallax is then known exactly);
* the six-point solution by least squares from the checker's own design (residuals and
  redundancy numbers), against which an answer from the condition's coefficients alone is judged;
* a pair of exterior orientations built from known elements of the dependent pair (the right
  projection centre and rotation put where the elements say), which must come back.

Model units (mm at machine or image scale), model Z < 0 below the base, angles rad inside,
gon where the exercise says so.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from ..camera import project

# the library's relative orientation: forbidden in the checks (own_work), never an oracle
from ..orientation.relative import design_dependent as library_design_dependent
from ..orientation.relative import relative_orientation, y_parallax_jacobian
from ..orientation.relative import y_parallax as library_y_parallax
from ..orientation.schemes import (
    condition_equation,
    condition_misclosure,
    influence,
    scheme_precision,
)
from ..rotation import matrix_from_opk, opk_from_matrix
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
from .lesson02 import _rodrigues_opk

__all__ = [
    "check_condition",
    "check_design",
    "check_middle_users",
    "check_parallax",
    "check_relative_from_exterior",
    "check_scheme_sigma",
    "check_six_point_residuals",
]

F64 = NDArray[np.float64]
GON = np.pi / 200.0


def _rigorous_parallax(P: F64, e: F64, b: float, c: float = 152.7) -> F64:
    """p_y of model points P for a right image taken with elements e = (by, bz, ω, φ, κ) [mm, rad]."""
    xy1 = -c * P[:, :2] / P[:, 2:]
    R = _rodrigues_opk(*e[2:], unit=1.0)
    uvw = (P - np.array([b, e[0], e[1]])) @ R
    xy2 = -c * uvw[:, :2] / uvw[:, 2:]
    lam = b / (xy1[:, 0] - xy2[:, 0])  # both rays at the same depth in the XZ projection
    return lam * (xy1[:, 1] - xy2[:, 1])


def _numeric_design(P: F64, b: float, h: float = 1e-7) -> F64:
    return np.column_stack(
        [
            (_rigorous_parallax(P, e, b) - _rigorous_parallax(P, -e, b)) / (2 * h)
            for e in np.eye(5) * h
        ]
    )


def _points(rng: np.random.Generator, n: int, b: float, relief: float = 0.15) -> F64:
    return np.column_stack(
        [
            rng.uniform(0, b, n),
            rng.uniform(-100, 100, n),
            -152.7 * (1 + relief * rng.uniform(-0.5, 0.5, n)),
        ]
    )


@own_work(
    "the exercise is the derivation of the linearised equation; differences of the library's "
    "parallax or projection skip it",
    design_dependent=library_design_dependent,
    y_parallax_jacobian=y_parallax_jacobian,
    y_parallax=library_y_parallax,
    project=project,
)
def check_design(design_dependent: Callable[[F64, F64, F64, float], F64]) -> None:
    """``design_dependent(X, Y, Z, b)`` must return ∂p_y/∂(by, bz, ω, φ, κ), shape (n, 5).

    The answer may not call the library's ``design_dependent`` (the lesson's stand-in) or
    ``y_parallax_jacobian``."""
    rng = rng_for("lesson05.check_design")
    b = 92.0
    P = _points(rng, 7, b)
    truth = _numeric_design(P, b)
    got = call(
        design_dependent, P[:, 0].copy(), P[:, 1].copy(), P[:, 2].copy(), b, what="design_dependent"
    )
    wrong = [
        ("it is p = y″ − y′ with the opposite sign throughout", -truth),
        ("the φ and κ columns are swapped", truth[:, [0, 1, 2, 4, 3]]),
        (
            "Kovarik's signs: his bz and κ are counted the other way round",
            truth * [1, -1, 1, 1, -1],
        ),
    ]
    q = P[:, 1] / P[:, 2]
    omega_minus = truth.copy()
    omega_minus[:, 2] = -P[:, 2] * (1 - q * q)
    wrong.append(("the ω column is −Z(1 − Y²/Z²): the sign inside the bracket is +, −Z(1 + Y²/Z²)",
                  omega_minus))  # fmt: skip
    compare("∂p_y/∂(by, bz, ω, φ, κ)", got, truth, rtol=1e-5, wrong=wrong)
    exact = complex_step(lambda e: _rigorous_parallax(P, e, b), np.zeros(5))
    exact_derivatives("∂p_y/∂(by, bz, ω, φ, κ)", got, exact)
    success("design matrix: each column is the derivative of the rigorous y-parallax")


NAMES = ("by", "bz", "omega", "phi", "kappa")


def _kovarik_nine(b: float, d: float, Z: F64) -> F64:
    """Kovarik's nine points (profiles X = 0, b, then the middle b/2; rows Y = 0, +d, −d)."""
    X = np.array([0, b, 0, b, 0, b, b / 2, b / 2, b / 2])
    Y = np.array([0, 0, d, d, -d, -d, d, 0, -d])
    return np.column_stack([X, Y, Z])


@own_work(
    "G is the influence matrix of your design_dependent (write that first: the library's stands "
    "in only while your blank is empty)",
    influence=influence,
    design_dependent=library_design_dependent,
)
def check_middle_users(fn: Callable) -> None:
    """Check ``fn(X, Y, Z, b) -> names``: the elements (of "by", "bz", "omega", "phi", "kappa")
    on which Kovarik's middle profile (the last three of nine points) has an influence, i.e. a
    non-zero entry of G = (AᵀA)⁻¹Aᵀ relative to the element's largest.

    Oracle: G from the pseudo-inverse of a central-difference design of the rigorous
    y-parallax (the checker's own), threshold 1e-6 of each row's largest entry; five height
    patterns (flat, a hill under the middle profile, single outer points raised, random)."""
    rng = rng_for("lesson05.check_middle_users")
    b, d, H = 92.0, 100.0, -152.7
    patterns = {
        "flat terrain": np.full(9, H),
        "the middle profile on a hill (its Z 20 % shorter)": np.r_[
            np.full(6, H), np.full(3, 0.8 * H)
        ],
        "point 1 (left profile, base line) raised": np.r_[0.8 * H, np.full(8, H)],
        "point 3 (left profile, upper row) raised": np.r_[H, H, 0.8 * H, np.full(6, H)],
        "random relief": H * (1 + 0.3 * rng.uniform(-0.5, 0.5, 9)),
    }
    for what, Z in patterns.items():
        P = _kovarik_nine(b, d, Z)
        A = _numeric_design(P, b)
        G = np.linalg.pinv(A)
        want = {
            n for j, n in enumerate(NAMES) if np.abs(G[j, 6:]).max() > 1e-6 * np.abs(G[j]).max()
        }
        got = call(fn, P[:, 0].copy(), P[:, 1].copy(), P[:, 2].copy(), b, what="middle_users")
        try:
            got = {str(g) for g in got}
        except TypeError:
            raise CheckFailed(f"middle_users: expected names of elements, got {got!r}") from None
        if not got <= set(NAMES):
            raise CheckFailed(
                f"middle_users: unknown names {sorted(got - set(NAMES))}; use {NAMES}"
            )
        if got == want:
            continue
        from_A = {
            n for j, n in enumerate(NAMES) if np.abs(A[6:, j]).max() > 1e-6 * np.abs(A[:, j]).max()
        }
        first = {
            n for j, n in enumerate(NAMES) if np.abs(G[j, :3]).max() > 1e-6 * np.abs(G[j]).max()
        }
        reasons = []
        if got == from_A:
            reasons.append("these are the elements that act ON the middle points (the design A); "
                           "which points an element listens TO is its row of the influence matrix "
                           "G = (AᵀA)⁻¹Aᵀ")  # fmt: skip
        if got == first:
            reasons.append("these are the first three points' influences; the middle profile is "
                           "points 7, 8, 9 (the last three)")  # fmt: skip
        why = (
            " — or: ".join(reasons)
            or f"missing {sorted(want - got)}, not influenced {sorted(got - want)}"
        )
        raise CheckFailed(f"middle_users ({what}): {sorted(got)}, expected {sorted(want)} — {why}")
    success(
        "the middle profile's influence for flat ground, a hill under it, raised outer points and random relief"
    )


@own_work(y_parallax=library_y_parallax)
def check_parallax(y_parallax: Callable[[F64, F64, float], F64]) -> None:
    """``y_parallax(xy1, xy2, b)`` must return p_y = Y_left − Y_right (n,) of a normal-case pair, model mm.

    The answer may not call the library's ``y_parallax`` (the lesson's stand-in)."""
    rng = rng_for("lesson05.check_parallax")
    b, c = 92.0, 152.7
    P = _points(rng, 6, b)
    gap = rng.uniform(-0.3, 0.3, 6)
    xy1 = -c * P[:, :2] / P[:, 2:]
    Q = (
        P + np.column_stack([np.zeros(6), gap, np.zeros(6)]) - [b, 0, 0]
    )  # the right ray passes Y + gap
    xy2 = -c * Q[:, :2] / Q[:, 2:]
    truth = -gap  # Y_left − Y_right
    got = call(y_parallax, xy1.copy(), xy2.copy(), b, what="y_parallax")
    wrong = [
        ("this is Y_right − Y_left", gap),
        (
            "y′ − y″ is an image difference: scale it to the model with λ = b / (x′ − x″)",
            xy1[:, 1] - xy2[:, 1],
        ),
    ]
    compare("p_y [model mm]", got, truth, rtol=1e-9, scale=0.3, wrong=wrong)
    success("y-parallax read where the two rays meet in the XZ projection")


def _gruber(b: float, d: float, h: float) -> F64:
    """Gruber's six points: profiles X = 0 and X = b, rows Y = 0, +d, −d, flat at Z = −h."""
    return np.array(
        [[0, 0, -h], [b, 0, -h], [0, d, -h], [b, d, -h], [0, -d, -h], [b, -d, -h]], dtype=float
    )


def check_six_point_residuals(
    six_point_residuals: Callable[[F64, F64], tuple[F64, F64]],
) -> None:
    """``six_point_residuals(p, w) -> (v, r)`` of Gruber's six points from the parallaxes and
    the condition's coefficients alone.

    v = A d̂ − p are the residuals of the least-squares elements (model mm) and r the
    redundancy numbers, both shape (6,); ``w`` (6,) spans the left null space of the design
    (wᵀA = 0), scaled as the check likes (not to unit length). Oracle: the elements solved by
    least squares from the checker's central-difference design, and r = 1 − diag(A A⁺) — not the
    condition vector. Flat ground and a model with 30 % relief; one parallax misread by 50 µm.
    """
    rng = rng_for("lesson05.check_six_point_residuals")
    for b, d, h, relief, scale in (
        (92.0, 100.0, 152.7, 0.0, 2.0),
        (220.7, 110.0, 366.0, 0.3, -0.7),
    ):
        P = _gruber_relief(rng, b, d, h, relief)
        A = _numeric_design(P, b)
        w = np.linalg.svd(A.T)[2][-1]
        w = w * scale / w[0]  # first coefficient 2 (the lesson's scaling), then another
        p = A @ np.r_[rng.uniform(-0.5, 0.5, 2), rng.uniform(-0.01, 0.01, 3)]
        p[rng.integers(6)] += 0.05  # one parallax misread by 50 µm
        v_true = A @ np.linalg.lstsq(A, p, rcond=None)[0] - p
        r_true = 1.0 - np.diag(A @ np.linalg.pinv(A))
        got = call(six_point_residuals, p.copy(), w.copy(), what="six_point_residuals")
        try:
            v, r = got
        except (TypeError, ValueError):
            raise CheckFailed(
                "six_point_residuals must return two arrays (v, r), each of shape (6,)."
            ) from None
        where = "flat ground" if relief == 0.0 else "30 % relief"
        wn = w / np.linalg.norm(w)
        compare(
            f"residuals v [model mm] ({where})",
            v,
            v_true,
            rtol=1e-5,
            wrong=[
                ("this is p − A d̂; the lesson's residuals are v = A d̂ − p (computed − observed)",
                 -v_true),
                ("these are the parallaxes p themselves, not what the solution leaves of them", p),
                ("w (wᵀp) without dividing by wᵀw: w is not a unit vector here",
                 -w * (w @ p)),
            ],
        )  # fmt: skip
        compare(
            f"redundancy numbers r ({where})",
            r,
            r_true,
            rtol=1e-5,
            scale=1.0,
            wrong=[
                ("this is the diagonal of A(AᵀA)⁻¹Aᵀ, the share of each parallax that goes into "
                 "the elements; r_i is what is left, 1 minus that", 1.0 - r_true),
                ("every point got (n − u)/n = 1/6, the mean share; r_i differs from point to point",
                 np.full(6, 1.0 / 6.0)),
                ("these sum to 1 but are |w_i|/Σ|w|: r_i is quadratic in the condition's "
                 "coefficients", np.abs(w) / np.abs(w).sum()),
                ("w_i² without dividing by wᵀw: w is not a unit vector here", w * w),
                ("w_i/|w|: the diagonal of a projector onto w is quadratic in w", np.abs(wn)),
            ],
        )  # fmt: skip
    success(
        "six points: residuals and redundancy numbers from the condition alone, flat and with relief"
    )


def _gruber_relief(rng: np.random.Generator, b: float, d: float, h: float, relief: float) -> F64:
    P = _gruber(b, d, h)
    P[:, 2] *= 1 + relief * rng.uniform(-0.5, 0.5, 6)
    P[:, 1] *= -P[:, 2] / h  # keep the edge rows at Y/Z = ∓d/h
    return P


@own_work(
    "the exercise is the condition from your own design matrix",
    condition_misclosure=condition_misclosure,
    condition_equation=condition_equation,
)
def check_condition(misclosure: Callable[[F64, F64, F64, F64, float], float]) -> None:
    """``misclosure(p, X, Y, Z, b)`` for Gruber's six points must return w = wᵀp, w in the left null space of A, w₁ = 2."""
    rng = rng_for("lesson05.check_condition")
    b, d, h = 220.7, 110.0, 366.0
    for relief in (0.0, 0.25):
        P = _gruber_relief(rng, b, d, h, relief)
        A = _numeric_design(P, b)
        w = np.linalg.svd(A.T)[2][-1]
        w = 2.0 * w / w[0]
        flat = np.array([2.0, -2.0, -1.0, 1.0, -1.0, 1.0])
        p = A @ (rng.uniform(-0.5, 0.5, 5) * [1, 1, 0.01, 0.01, 0.01])
        k = int(rng.integers(1, 6))
        for label, pp in (
            ("a consistent model", p),
            (f"point {k + 1} misread by 50 µm", p + 0.05 * np.eye(6)[k]),
        ):
            got = float(
                call(
                    misclosure,
                    pp.copy(),
                    P[:, 0].copy(),
                    P[:, 1].copy(),
                    P[:, 2].copy(),
                    b,
                    what="misclosure",
                )
            )
            wrong = [
                (
                    "this is the flat-terrain form: with relief use the null vector of your design matrix",
                    flat @ pp,
                ),
                ("normalise the condition so that the coefficient of p1 is +2", -(w @ pp)),
            ]
            compare(
                f"misclosure for {label}, relief {relief:.0%}",
                got,
                w @ pp,
                rtol=1e-6,
                scale=0.05,
                wrong=wrong,
            )
    success("condition: zero for a consistent model, and it shows a misread parallax")


def _gruber_sigmas(b: float, d: float, h: float, sigma: float, how: str = "right") -> F64:
    """σ of (by, bz, ω, φ, κ) of Gruber's six flat points from the checker's numerical design
    (``how`` names a wrong variant)."""
    A = _numeric_design(_gruber(b, d / 2 if how == "spread" else d, h), b)
    N = A.T @ A
    if how == "diagonal":
        return sigma / np.sqrt(np.diag(N))
    q = np.diag(np.linalg.inv(N))
    if how == "variance":
        return sigma**2 * q
    if how == "sigma squared":
        return sigma**2 * np.sqrt(q)
    return sigma * np.sqrt(q)


@own_work(
    "the checker's oracle and the library's scheme precision are not an answer",
    _gruber_sigmas=_gruber_sigmas,
    _numeric_design=_numeric_design,
    scheme_precision=scheme_precision,
    influence=influence,
)
def check_scheme_sigma(scheme_sigmas: Callable[[float, float, float, float], F64]) -> None:
    """``scheme_sigmas(d, sigma, b, h)``: σ of (by, bz, ω, φ, κ) [model mm, rad] of Gruber's six
    points on flat ground (profiles X = 0 and X = b, rows Y = 0 and ±d, Z = −h), σ per
    parallax reading (model mm)."""
    rng = rng_for("lesson05.check_scheme_sigma")
    for _ in range(3):
        b, h = rng.uniform(180.0, 240.0), rng.uniform(300.0, 420.0)
        d, sigma = rng.uniform(80.0, 260.0), rng.uniform(0.003, 0.008)
        truth = _gruber_sigmas(b, d, h, sigma)
        got = call(scheme_sigmas, d, sigma, b, h, what="scheme_sigmas")
        wrong = [
            (
                "take the diagonal of (AᵀA)⁻¹, not the inverse of the diagonal of AᵀA: the "
                "elements are correlated",
                _gruber_sigmas(b, d, h, sigma, "diagonal"),
            ),
            ("the square root is missing (these are variances)",
             _gruber_sigmas(b, d, h, sigma, "variance")),
            ("multiply by σ, not σ²", _gruber_sigmas(b, d, h, sigma, "sigma squared")),
            ("d is each outer row's distance from the middle row (Y = ±d), not the distance "
             "between the two outer rows", _gruber_sigmas(b, d, h, sigma, "spread")),
        ]  # fmt: skip
        compare(f"σ of (by, bz, ω, φ, κ) for d = {d:.0f}, h = {h:.0f} mm", got, truth, rtol=1e-5,
                wrong=wrong)  # fmt: skip
    success("σ of the five elements of Gruber's six points, three schemes (numerical design)")


@own_work(
    "the iteration is yours, with your rigorous parallax and your design_dependent (write "
    "that first: the library's stands in only while your blank is empty)",
    relative_orientation=relative_orientation,
    y_parallax=library_y_parallax,
    design_dependent=library_design_dependent,
)
def check_kovarik_iteration(fn: Callable) -> None:
    """``fn(xy1, xy2, c, b) -> (elements, steps)``: the whole iteration of the dependent relative
    orientation — rigorous y-parallaxes of the current pair, the five corrections by least
    squares with the linearised parallax equation, applied, repeated — from the normal case;
    elements (by, bz mm; ω, φ, κ rad) of the right projector."""
    rng = rng_for("lesson05.check_kovarik_iteration")
    c, b = 121.3, 81.0
    n = 12
    P = np.column_stack([rng.uniform(-5, b + 5, n), rng.uniform(-90, 90, n),
                         -c * (1 + 0.2 * rng.uniform(-0.5, 0.5, n))])  # fmt: skip
    truth = np.array([0.35, -0.22, 14 * GON / 100, -9 * GON / 100, 17 * GON / 100])  # 14, −9, 17 c
    xy1 = project(P, np.zeros(3), np.eye(3), c)
    xy2 = project(P, np.array([b, truth[0], truth[1]]), matrix_from_opk(*truth[2:]), c)
    got = call(fn, xy1.copy(), xy2.copy(), c, b, what="kovarik_iteration")
    if not isinstance(got, tuple) or len(got) != 2:
        raise CheckFailed("kovarik_iteration: return (elements, steps)")
    e = np.asarray(got[0], dtype=float)
    if e.shape != (5,):
        raise CheckFailed(f"elements: expected (by, bz, ω, φ, κ), shape (5,), got {e.shape}")
    steps = list(got[1])
    if len(steps) < 3:
        raise CheckFailed(
            f"only {len(steps)} step(s): one linear solution is not the iteration — repeat until "
            "the corrections vanish",
            float(np.abs(e - truth).max() / 0.01),
            1e-8,
        )
    if not np.all(np.isfinite(e)) or np.abs(e[:2]).max() > 10.0 or np.abs(e[2:]).max() > 1.0:
        raise CheckFailed(
            "the iteration runs away (elements of "
            f"{np.round(e, 3).tolist()}): a sign is wrong — the parallax is p_y = Y_left − Y_right, "
            "the corrections are added, and the right ray is R (x'', y'', −c) (row-wise d2 @ Rᵀ)"
        )
    size = np.abs(np.asarray([float(np.max(np.abs(s))) for s in steps]))
    if not np.all(np.isfinite(size)) or size[-1] > 1e-6 or size[-1] > 1e-3 * size[0]:
        raise CheckFailed(
            f"the steps do not shrink to zero (first {size[0]:.1e}, last {size[-1]:.1e}): return "
            "the size of each correction (e.g. its largest element) and iterate until the last one "
            "is tiny (< 1e-6)"
        )
    compare("by, bz [mm] of an error-free pair", e[:2], truth[:2], rtol=1e-8, scale=1.0)
    pok = np.asarray(opk_from_matrix(matrix_from_opk(*truth[2:]), "pok"), dtype=float)
    compare(
        "ω, φ, κ [rad] of an error-free pair", e[2:], truth[2:], rtol=1e-8, scale=0.01, unit="rad",
        wrong=[("the φ-ω-κ sequence of the plotter: the pair here is built with ω-φ-κ, "
                "R = R_ω R_φ R_κ (`ov.matrix_from_opk(ω, φ, κ)`)", pok)],
    )  # fmt: skip
    success(f"the error-free pair's elements come back after {len(steps)} steps "
            f"(last correction {steps[-1]:.1e})")  # fmt: skip


def _opk(R: F64) -> F64:
    """ω, φ, κ (rad) of R = R_ω R_φ R_κ, read from its entries (abs(φ) < 100 gon)."""
    return np.array(
        [np.arctan2(-R[1, 2], R[2, 2]), np.arcsin(R[0, 2]), np.arctan2(-R[0, 1], R[0, 0])]
    )


@own_work(relative_orientation=relative_orientation)
def check_relative_from_exterior(relative_from_exterior: Callable[..., F64]) -> None:
    """``relative_from_exterior(X01, R1, X02, R2, b)`` must return the dependent pair's elements
    (by, bz [model mm], ω, φ, κ [rad]) of two exterior orientations (m; R image → object),
    the left image fixed and the model base b along the left image's x axis."""
    rng = rng_for("lesson05.check_relative_from_exterior")
    for _ in range(3):
        e = np.r_[rng.uniform(-0.8, 0.8, 2), rng.uniform(-0.03, 0.03, 3)]  # mm, rad
        b = rng.uniform(12.0, 90.0)
        R1 = _rodrigues_opk(*rng.uniform(-0.04, 0.04, 2), rng.uniform(1.3, 1.8), unit=1.0)
        X01 = np.array([rng.uniform(-1e3, 1e3), rng.uniform(-1e3, 1e3), rng.uniform(1500, 2000)])
        scale = rng.uniform(5.0, 20.0)  # m of object space per model mm
        X02 = X01 + scale * R1 @ np.array([b, e[0], e[1]])
        R2 = R1 @ _rodrigues_opk(*e[2:], unit=1.0)
        got = np.asarray(
            call(
                relative_from_exterior,
                X01.copy(),
                R1.copy(),
                X02.copy(),
                R2.copy(),
                b,
                what="relative_from_exterior",
            ),  # fmt: skip
            dtype=float,
        )
        if got.shape != (5,):
            raise CheckFailed(
                f"relative_from_exterior: expected 5 elements (by, bz, ω, φ, κ), got shape {got.shape}."
            )
        B_obj = (X02 - X01) * b / (X02 - X01)[0]
        B_unscaled = R1.T @ (X02 - X01)
        wrong_base = [
            ("the base is taken in the object frame: rotate it into the left image first, "
             "Bᵀ = R1ᵀ(X02 − X01)", B_obj[1:]),
            ("the base is not scaled so that its x component is b (model mm)", B_unscaled[1:]),
        ]  # fmt: skip
        compare("by, bz [model mm]", got[:2], e[:2], rtol=1e-8, scale=b, wrong=wrong_base)
        wrong_rot = [
            ("these are the angles of R2ᵀR1: R transposed (the relative rotation is R1ᵀR2)",
             _opk(R2.T @ R1)),
            ("these are the angles of R2R1ᵀ, a rotation in the object frame (the relative "
             "rotation is R1ᵀR2, in the left image's frame)", _opk(R2 @ R1.T)),
            ("these are the angles of the right image alone, not relative to the left one",
             _opk(R2)),
        ]  # fmt: skip
        compare("ω, φ, κ [rad]", got[2:], e[2:], rtol=1e-8, unit="rad", wrong=wrong_rot, scale=0.03)
    success("relative_from_exterior: the elements the pair was built with come back")
