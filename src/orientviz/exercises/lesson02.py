"""Checkers for lesson 02, rotations and the collinearity equations.

Oracles (never :func:`orientviz.rotation.matrix_from_opk` or :func:`orientviz.camera.project`):
rotations are built here from Rodrigues' formula about the object axes, and image points
are made backwards: a ray ``X = X0 + λ R (x − x0, y − y0, −c)`` through a chosen image
point gives an object point whose image is known exactly.

Angles are in gon (400 gon to the circle), rotations R = R_ω R_φ R_κ (image → object).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..camera import project  # forbidden inside the student's functions (own_work)
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

__all__ = [
    "check_collinearity",
    "check_gimbal_pok",
    "check_ground_point",
    "check_opk_from_matrix",
    "check_relief_displacement",
    "check_rotation",
    "check_vertical_partials",
]

F64 = NDArray[np.float64]
GON = np.pi / 200.0


def _axis_rotation(axis: F64, angle: float) -> F64:
    """Rodrigues: rotation by ``angle`` (rad, right-handed) about the unit vector ``axis``."""
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * (K @ K)


def _rodrigues_opk(
    omega: float, phi: float, kappa: float, unit: float = GON, order: str = "opk"
) -> F64:
    """The oracle: R = R_X(ω) R_Y(φ) R_Z(κ) as a product of Rodrigues rotations (angles × unit → rad)."""
    rot = {
        "o": _axis_rotation(np.array([1.0, 0, 0]), omega * unit),
        "p": _axis_rotation(np.array([0, 1.0, 0]), phi * unit),
        "k": _axis_rotation(np.array([0, 0, 1.0]), kappa * unit),
    }
    return rot[order[0]] @ rot[order[1]] @ rot[order[2]]


@own_work(matrix_from_opk=matrix_from_opk)
def check_rotation(R_opk: Callable[[float, float, float], F64]) -> None:
    """``R_opk(omega, phi, kappa)`` (gon) must return R = R_ω R_φ R_κ, shape (3, 3)."""
    # a case by hand: κ = 100 gon alone turns image x into object Y
    hand = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    got = call(R_opk, 0.0, 0.0, 100.0, what="R_opk")
    compare(
        "R_opk(0, 0, 100 gon)",
        got,
        hand,
        rtol=1e-9,
        wrong=[("the angle was read as degrees, not gon", _rodrigues_opk(0, 0, 100, np.pi / 180))],
    )
    rng = rng_for("lesson02.check_rotation")
    for angles in ([12.0, -31.0, 57.0], list(rng.uniform(-150, 150, 3))):
        w, p, k = (float(a) for a in angles)
        truth = _rodrigues_opk(w, p, k)
        sign_phi = _rodrigues_opk(w, -p, k)  # a flipped sine in R_φ turns φ into −φ
        wrong = [
            ("the angles were read as degrees, not gon", _rodrigues_opk(w, p, k, np.pi / 180)),
            ("the angles were read as radians, not gon", _rodrigues_opk(w, p, k, 1.0)),
            ("this is R_φ R_ω R_κ (φ-ω-κ), not R_ω R_φ R_κ", _rodrigues_opk(w, p, k, order="pok")),
            (
                "this is R_κ R_φ R_ω (the factors in reverse order)",
                _rodrigues_opk(w, p, k, order="kpo"),
            ),
            ("the sine terms of R_φ have the wrong signs", sign_phi),
        ]
        got = call(R_opk, w, p, k, what="R_opk")
        compare(f"R_opk({w:.3f}, {p:.3f}, {k:.3f} gon)", got, truth, rtol=1e-9, wrong=wrong)
    success("R = R_ω R_φ R_κ from gon, as Rodrigues' rotations about X, Y, Z give it")


def _rays_to_points(xy: F64, X0: F64, R: F64, c: float, x0: float, y0: float, depth: F64) -> F64:
    """Object points on the rays of ``xy`` at ``depth`` (m along −w): the oracle's scene."""
    d = np.column_stack([xy[:, 0] - x0, xy[:, 1] - y0, np.full(len(xy), -c)]) / c
    return X0 + depth[:, None] * (d @ R.T)


@own_work(project=project)
def check_collinearity(collinearity: Callable[..., F64]) -> None:
    """``collinearity(X, X0, R, c, x0, y0)`` must return the image coordinates (n, 2) in mm."""
    rng = rng_for("lesson02.check_collinearity")
    R = _rodrigues_opk(*rng.uniform(-15, 15, 2), rng.uniform(-200, 200))
    X0 = np.array([512.0, -230.0, 1480.0])
    c, x0, y0 = 152.7, 0.013, -0.021
    xy = rng.uniform(-110, 110, (8, 2))
    X = _rays_to_points(xy, X0, R, c, x0, y0, rng.uniform(1300, 1600, 8))
    uvw_R = (X - X0) @ R.T  # R instead of Rᵀ
    uvw = (X - X0) @ R
    wrong = [
        (
            "you turned the vector with R instead of Rᵀ",
            np.column_stack(
                [x0 - c * uvw_R[:, 0] / uvw_R[:, 2], y0 - c * uvw_R[:, 1] / uvw_R[:, 2]]
            ),
        ),
        (
            "the sign of c is wrong (x = x0 + c u/w?)",
            np.column_stack([x0 + c * uvw[:, 0] / uvw[:, 2], y0 + c * uvw[:, 1] / uvw[:, 2]]),
        ),
        ("the principal point x0, y0 is missing", xy - [x0, y0]),
        ("x and y are swapped", xy[:, ::-1]),
    ]
    got = call(collinearity, X, X0, R, c, x0, y0, what="collinearity")
    compare("image coordinates [mm]", got, xy, rtol=1e-9, scale=100.0, wrong=wrong)
    success("collinearity: the image points lie where their rays were drawn from")


def _R_pok(phi: float, omega: float, kappa: float) -> F64:
    """R = R_φ R_ω R_κ (φ-ω-κ, analogue plotters), gon, by Rodrigues' rotations."""
    return _rodrigues_opk(omega, phi, kappa, order="pok")


def check_gimbal_pok(locked_phi: Callable[[float, float, float], float]) -> None:
    """``locked_phi(phi, kappa, omega)`` (gon, ω = ±100) must return φ' with
    R_φ(φ') R_ω(ω) = R_φ(φ) R_ω(ω) R_κ(κ) in the φ-ω-κ sequence."""
    rng = rng_for("lesson02.check_gimbal_pok")
    for omega in (100.0, -100.0):
        p, k = (float(a) for a in rng.uniform(-60, 60, 2))
        got = float(call(locked_phi, p, k, omega, what="locked_phi"))
        truth = _R_pok(p, omega, k)
        wrong = [
            ("that is the ω-φ-κ rule (ω + κ at +100 gon): in φ-ω-κ, R_ω(+100 gon) turns the κ "
             "axis into −Y, so the sign is reversed — work it out with R_ω e_Z",
             _R_pok(p + np.sign(omega) * k, omega, 0.0)),
            ("κ is missing: at ω = ±100 gon κ turns about the same axis as φ",
             _R_pok(p, omega, 0.0)),
        ]  # fmt: skip
        compare(f"R(φ', {omega:+.0f}, 0) for φ = {p:.3f}, κ = {k:.3f} gon",
                _R_pok(got, omega, 0.0), truth, rtol=1e-9, wrong=wrong)  # fmt: skip
    success("at ω = ±100 gon in φ-ω-κ only φ ∓ κ counts: φ and κ turn about one axis")


@own_work(opk_from_matrix=opk_from_matrix)
def check_opk_from_matrix(angles_from_R: Callable[[F64], ArrayLike]) -> None:
    """``angles_from_R(R)`` must return (ω, φ, κ) in gon with R = R_ω R_φ R_κ, abs(φ) < 100 gon."""
    rng = rng_for("lesson02.check_opk_from_matrix")
    cases = [
        np.array([rng.uniform(-180, 180), rng.uniform(-90, 90), rng.uniform(-180, 180)])
        for _ in range(3)
    ]
    cases.append(np.array([152.0, 31.0, -171.0]))  # cos ω < 0 and cos κ < 0: the quadrant matters
    for truth in cases:
        R = _rodrigues_opk(*truth)
        got = call(angles_from_R, R, what="angles_from_R")
        g = np.asarray(got, dtype=float)
        if g.shape == (3,) and np.all(np.isfinite(g)):
            # the angles put back into R = R_ω R_φ R_κ (Rodrigues): do they give Rᵀ?
            Rg = _rodrigues_opk(*g)
            if np.abs(Rg - R.T).max() < 1e-9 and np.abs(R - R.T).max() > 1e-6:
                err = float(np.abs(g - truth).max() / 200.0)
                raise CheckFailed(
                    f"(ω, φ, κ) [gon]: wrong (relative difference {err:.3g}, allowed 1e-09) — "
                    "these are the angles of Rᵀ (R turns image vectors into the object frame).",
                    err,
                    1e-9,
                )
        quadrant = np.array(
            [
                np.arctan(-R[1, 2] / R[2, 2]) / GON,
                np.arcsin(np.clip(R[0, 2], -1.0, 1.0)) / GON,
                np.arctan(-R[0, 1] / R[0, 0]) / GON,
            ]
        )
        wrong = [
            ("the sign of ω is wrong", truth * [-1, 1, 1]),
            ("the sign of κ is wrong", truth * [1, 1, -1]),
            ("the sign of φ is wrong", truth * [1, -1, 1]),
            ("arctan loses the quadrant (here cos ω < 0 and cos κ < 0): use arctan2 of the two "
             "elements, not arctan of their ratio", quadrant),
        ]  # fmt: skip
        compare("(ω, φ, κ) [gon]", got, truth, rtol=1e-9, unit="gon", wrong=wrong, scale=200.0)
    success("ω, φ, κ read back from R (in gon)")


def check_ground_point(ground_point: Callable[..., F64]) -> None:
    """``ground_point(xy, X0, R, c, Z)`` must return the object points (n, 3) on the plane Z."""
    rng = rng_for("lesson02.check_ground_point")
    R = _rodrigues_opk(*rng.uniform(-10, 10, 2), rng.uniform(-200, 200))
    X0 = np.array([1200.0, 830.0, 1620.0])
    c, Z = 152.7, 212.0
    truth = np.column_stack([rng.uniform(500, 1900, 6), rng.uniform(200, 1500, 6), np.full(6, Z)])
    uvw = (truth - X0) @ R
    xy = -c * uvw[:, :2] / uvw[:, 2:]

    def plane(Rm: F64, cc: float) -> F64:
        d = np.column_stack([xy, np.full(len(xy), -cc)]) @ Rm.T
        return X0 + ((Z - X0[2]) / d[:, 2])[:, None] * d

    wrong = [
        ("the image vector was turned with Rᵀ instead of R", plane(R.T, c)),
        ("the image vector needs z = −c, not +c", plane(R, -c)),
    ]
    got = call(ground_point, xy, X0, R, c, Z, what="ground_point")
    compare("ground points [m]", got, truth, rtol=1e-9, scale=1000.0, wrong=wrong)
    success("ground points: the rays meet the plane where the points were")


def _vertical_closed_forms(x: F64, y: F64, c: float, one: float = 1.0) -> F64:
    """∂(x, y)/∂(ω, φ, κ) of a vertical image (n, 2, 3), mm/rad; ``one = 0`` drops the 1 in
    c(1 + x²/c²) — a plausible slip the check names."""
    J = np.zeros((len(x), 2, 3))
    J[:, 0, 0], J[:, 1, 0] = -x * y / c, -c * (one + y**2 / c**2)
    J[:, 0, 1], J[:, 1, 1] = c * (one + x**2 / c**2), x * y / c
    J[:, 0, 2], J[:, 1, 2] = y, -x
    return J


def check_vertical_partials(vertical_partials: Callable[[F64, float], ArrayLike]) -> None:
    """``vertical_partials(xy, c)`` must return ∂(x, y)/∂(ω, φ, κ), shape (n, 2, 3), in mm/rad,
    of a vertical image (R = I, principal point at 0) at its image points ``xy`` (n, 2) mm.

    Oracle: central differences (h = 1e-6 rad) of the image points of object points drawn on
    the rays, projected through Rodrigues rotations by ±h about X, Y, Z.
    """
    rng = rng_for("lesson02.check_vertical_partials")
    c = float(rng.uniform(100.0, 160.0))
    xy = rng.uniform(-110.0, 110.0, (7, 2))
    X0 = np.array([350.0, -120.0, 1500.0])
    X = _rays_to_points(xy, X0, np.eye(3), c, 0.0, 0.0, rng.uniform(1300.0, 1700.0, 7))

    def image(R: F64) -> F64:
        uvw = (X - X0) @ R
        return -c * uvw[:, :2] / uvw[:, 2:]

    h = 1e-6
    truth = np.zeros((len(xy), 2, 3))
    for a in range(3):
        e = np.zeros(3)
        e[a] = h
        plus, minus = _rodrigues_opk(*e, unit=1.0), _rodrigues_opk(*-e, unit=1.0)
        truth[:, :, a] = (image(plus) - image(minus)) / (2.0 * h)
    x, y = xy.T
    closed = _vertical_closed_forms(x, y, c)
    if np.abs(closed - truth).max() > 1e-6 * np.abs(truth).max():  # pragma: no cover - oracle
        raise RuntimeError("lesson 02: the central differences disagree with the closed forms")
    kappa_swapped = closed.copy()
    kappa_swapped[:, 0, 2], kappa_swapped[:, 1, 2] = -y, x
    wrong = [
        (
            "every sign is reversed: (∂R/∂ω)ᵀ d = −Rᵀ(e_X × d), not +Rᵀ(e_X × d) ([a]×ᵀ = −[a]×)",
            -closed,
        ),
        (
            "the 1 in c(1 + x²/c²) and c(1 + y²/c²) is missing — ∂u/∂φ = −w (step 3) "
            "gives c·w/w = c",
            _vertical_closed_forms(x, y, c, one=0.0),
        ),
        ("the ω and φ columns are swapped", closed[:, :, [1, 0, 2]]),
        ("the κ column has the wrong sign (∂x/∂κ = +y, ∂y/∂κ = −x)", kappa_swapped),
        ("these are derivatives per gon, not per radian", closed * GON),
        ("these are derivatives per degree, not per radian", closed * np.pi / 180.0),
        ("x and y (the rows) are swapped", closed[:, ::-1, :]),
    ]
    got = call(vertical_partials, xy, c, what="vertical_partials")
    compare(
        "∂(x, y)/∂(ω, φ, κ) [mm/rad]",
        got,
        truth,
        rtol=1e-6,
        scale=float(np.abs(truth).max()),
        wrong=wrong,
    )
    exact = complex_step(lambda e: image(_rodrigues_opk(*e, unit=1.0)), np.zeros(3))
    exact_derivatives("∂(x, y)/∂(ω, φ, κ)", got, exact)
    success("∂(x, y)/∂(ω, φ, κ) of a vertical image: your closed forms = central differences")


def check_relief_displacement(relief_displacement: Callable[[F64, F64, float], F64]) -> None:
    """``relief_displacement(r_top, h, H)`` must return the radial displacement Δr (mm) of the
    top of a vertical object of height ``h`` (m) in a vertical photograph taken ``H`` (m) above
    the object's foot, from the radial distance ``r_top`` (mm) of the top's image.

    Oracle: the checker's own projection of the foot and the top of vertical objects.
    """
    rng = rng_for("lesson02.check_relief_displacement")
    c, H = 152.7, float(rng.uniform(1200.0, 1800.0))
    foot = np.column_stack([rng.uniform(-600, 600, 6), rng.uniform(-600, 600, 6), np.zeros(6)])
    h = rng.uniform(20.0, 300.0, 6)
    top = foot + np.column_stack([np.zeros((6, 2)), h])
    X0 = np.array([0.0, 0.0, H])

    def image(P: F64) -> F64:
        uvw = P - X0  # R = I
        return -c * uvw[:, :2] / uvw[:, 2:]

    r_foot = np.hypot(*image(foot).T)
    r_top = np.hypot(*image(top).T)
    truth = r_top - r_foot
    wrong = [
        ("this is r·h/(H − h): with r of the TOP the factor is h/H (h/(H − h) goes with the foot's r)",
         r_top * h / (H - h)),
        ("the sign is reversed: the top lies farther from the centre (away from the nadir)", -truth),
        ("h/H in different units: h and H are both in m, r in mm", r_top * h / (H * 1000.0)),
    ]  # fmt: skip
    got = call(relief_displacement, r_top.copy(), h.copy(), H, what="relief_displacement")
    compare("Δr [mm]", got, truth, rtol=1e-9, scale=float(np.abs(truth).max()), wrong=wrong)
    success("Δr = r·h/H with r of the top: the projected foot and top agree")
