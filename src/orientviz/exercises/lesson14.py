"""Checkers for lesson 14, the radar panorama image (Geier 1973).

Oracles: object points built *backwards* from chosen image coordinates, elevations and
ranges (so the image, the slant ranges and the station are known exactly), the mirror
image of a station in the plane of three points, and the true station of error-free
ranges — never the library's ``project``, ``sphere_radius`` or ``trilaterate_three``.
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
from orientviz.radar.orientation import station_by_trilateration
from orientviz.radar.ppi import sphere_radius
from orientviz.radar.scene import trilateration_scene


def _rodrigues(axis, angle: float) -> np.ndarray:
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _scene(rng: np.random.Generator, n: int = 9):
    """A station, a tilted axis and object points made from image coordinates (image m)."""
    X0 = np.array([30054.0, 28.0, 1039.9])
    R = _rodrigues([0.3, -0.7, 0.2], 0.05) @ _rodrigues([0, 0, 1], 0.9)
    h, m, x0, y0 = 1520.0, 1.1264, 434.2, 716.8
    theta = rng.uniform(-np.pi, np.pi, n)  # azimuths about the axis
    rho = rng.uniform(8000.0, 40000.0, n)  # image radii, image m
    s_e = rho / m
    s = np.sqrt(s_e**2 + h**2)  # slant range by Geier's Pythagoras
    c = -rng.uniform(0.02, 0.08, n) * s  # below the station, along the axis
    horiz = np.sqrt(s**2 - c**2)
    local = np.column_stack([horiz * np.cos(theta), horiz * np.sin(theta), c])
    P = X0 + local @ R.T
    xy = np.column_stack([x0 + rho * np.cos(theta), y0 + rho * np.sin(theta)])
    return dict(P=P, X0=X0, R=R, h=h, m=m, x0=x0, y0=y0, xy=xy, s=s)


def check_ppi_image(fn: Callable) -> None:
    """Check ``fn(P, X0, R, h, m, x0, y0) -> xy``: Geier's mapping equations (4a)."""
    sc = _scene(rng_for("lesson14.check_ppi_image"))
    got = call(
        fn,
        sc["P"].copy(),
        sc["X0"].copy(),
        sc["R"].copy(),
        sc["h"],
        sc["m"],
        sc["x0"],
        sc["y0"],
        what="ppi_image",
    )
    d = sc["P"] - sc["X0"]
    loc = d @ sc["R"]
    hor = np.hypot(loc[:, 0], loc[:, 1])
    pp = np.array([sc["x0"], sc["y0"]])
    wrong_true = pp + sc["m"] * loc[:, :2]  # the true horizontal range: no h
    loc_t = d @ sc["R"].T
    s_e = np.sqrt(np.sum(d**2, axis=1) - sc["h"] ** 2)
    wrong_R = (
        pp + sc["m"] * s_e[:, None] * loc_t[:, :2] / np.hypot(loc_t[:, 0], loc_t[:, 1])[:, None]
    )
    wrong_pp = sc["xy"] - pp
    wrong_hor = pp + sc["m"] * np.sqrt(hor**2 - sc["h"] ** 2)[:, None] * loc[:, :2] / hor[:, None]
    s = np.sqrt(np.sum(d**2, axis=1))
    wrong_no_h = pp + sc["m"] * s[:, None] * loc[:, :2] / hor[:, None]  # slant range, h left out
    compare(
        "image coordinates [image m]",
        got,
        sc["xy"],
        rtol=1e-9,
        scale=1000.0,
        wrong=[
            (
                "the true horizontal distance √(a² + b²) was plotted, not s_e = √(s² − h²)",
                wrong_true,
            ),
            ("R (X − X0) instead of Rᵀ (X − X0): the rotation goes image → object", wrong_R),
            ("the principal point (x0, y0) was not added", wrong_pp),
            ("h was subtracted from the horizontal distance, not from the slant range", wrong_hor),
            ("the slant range s was plotted: h is missing, s_e = √(s² − h²)", wrong_no_h),
        ],
    )
    success("the image of points built backwards from their image coordinates comes out exactly")


@own_work(
    "the library's sphere radius differenced numerically skips the derivation the exercise "
    "asks for",
    sphere_radius=sphere_radius,
)
def check_radius_change(fn: Callable) -> None:
    """Check ``fn(xy, x0, y0, m, h, dm) -> ds``: the first-order change of the range-sphere
    radius (4b) of each image point when the image scale m is wrong by ``dm`` (image m, m).

    Oracle: central differences of the sphere radius √((‖b‖/m)² + h²), evaluated here, for
    points from near the nadir (‖b‖/m ≪ h) to far out; compared per point relative to
    s_e·dm/m, so that near and far points count alike. The answer must be linear in dm
    (−3·dm gives −3 times the change): the finite change of (4b) evaluated twice is refused.
    """
    rng = rng_for("lesson14.check_radius_change")
    h, m, x0, y0 = 15020.0, 1.1264, 434.2, 716.8
    rho = np.r_[rng.uniform(1500.0, 6000.0, 4), rng.uniform(20000.0, 76000.0, 5)]  # image m
    theta = rng.uniform(-np.pi, np.pi, rho.size)
    xy = np.column_stack([x0 + rho * np.cos(theta), y0 + rho * np.sin(theta)])
    dm = 2e-4 * m

    def radius(mm: float) -> np.ndarray:
        return np.sqrt((rho / mm) ** 2 + h**2)

    eps = 1e-7 * m
    want = (radius(m + eps) - radius(m - eps)) / (2 * eps) * dm
    got = call(fn, xy.copy(), x0, y0, m, h, dm, what="radius_change")
    back = call(fn, xy.copy(), x0, y0, m, h, -3.0 * dm, what="radius_change")
    try:
        ratio = np.asarray(back, dtype=float) / np.asarray(got, dtype=float)
    except (TypeError, ValueError):
        raise CheckFailed(f"radius_change: expected one number per point, got {got!r}") from None
    if ratio.shape == rho.shape and np.max(np.abs(ratio + 3.0)) > 1e-9 * 3.0:
        raise CheckFailed(
            "radius_change: not linear in dm (−3·dm does not give −3 times the change): that is "
            "the finite change s(m + dm) − s(m); the first-order change ds = (ds/dm)·dm is asked "
            "— differentiate (4b)",
            error=float(np.max(np.abs(ratio + 3.0)) / 3.0),
            tolerance=1e-9,
        )
    s_e, s = rho / m, radius(m)
    unit = s_e * dm / m  # the change of s_e itself, per point
    try:
        g = np.asarray(got, dtype=float) / unit
    except (TypeError, ValueError):
        raise CheckFailed(f"radius_change: expected one number per point, got {got!r}") from None
    compare("ds per point, in units of s_e·dm/m", g, want / unit, rtol=1e-6, scale=1.0, wrong=[
        ("that is the change of s_e = |b|/m, not of s: the square root with h damps it by "
         "s_e/s (most near the nadir)", -np.ones_like(s)),
        ("the sign: a larger scale m makes every sphere smaller", -want / unit),
        ("the relative change ds/s, not ds", want / unit / s),
        ("s/s_e for s_e/s: the chain rule through √(s_e² + h²) gives s_e/s",
         -s / s_e),
    ])  # fmt: skip
    success(
        "ds = −(s_e²/s)·dm/m: from "
        f"{np.min(np.abs(want / unit)):.2f} to {np.max(np.abs(want / unit)):.2f} times the change "
        "of s_e (near the nadir to far out)"
    )


def _mirror(C: np.ndarray, X: np.ndarray) -> np.ndarray:
    n = np.cross(C[1] - C[0], C[2] - C[0])
    n /= np.linalg.norm(n)
    return X - 2 * ((X - C[0]) @ n) * n


@own_work(
    "the exercise is the intersection of three spheres, written by you",
    trilateration_scene=trilateration_scene,
    station_by_trilateration=station_by_trilateration,
)
def check_trilaterate(fn: Callable) -> None:
    """Check ``fn(C, r) -> (below, above)``: both points at distances r from the centres C."""
    rng = rng_for("lesson14.check_trilaterate")
    for _ in range(3):
        C = np.column_stack(
            [rng.uniform(-6000, 6000, 3), rng.uniform(-6000, 6000, 3), rng.uniform(-150, 250, 3)]
        )
        X = np.array([rng.uniform(20000, 35000), rng.uniform(-3000, 3000), rng.uniform(800, 1500)])
        r = np.linalg.norm(C - X, axis=1)
        other = _mirror(C, X)
        below, above = (X, other) if X[2] < other[2] else (other, X)
        out = call(fn, C.copy(), r.copy(), what="trilaterate")
        try:
            b, a = (np.asarray(v, float) for v in out)
        except (TypeError, ValueError):
            raise CheckFailed("return two points (below, above)") from None
        compare(
            "(below, above)",
            np.array([b, a]),
            np.array([below, above]),
            rtol=1e-8,
            scale=1000.0,
            wrong=[
                ("(above, below): give the lower candidate first", np.array([above, below])),
                (
                    "both candidates are the same point: take ±√ of the discriminant",
                    np.array([below, below]),
                ),
                (
                    "both candidates are the same point: take ±√ of the discriminant",
                    np.array([above, above]),
                ),
            ],
        )
    success("both candidates of three spheres found, ordered by Z")


def _station_sigma(C: np.ndarray, X0: np.ndarray, idx) -> np.ndarray:
    """σ of the station's X, Y, Z (units of the range σ) from ranges to the points ``idx``."""
    d = X0 - C[list(idx)]
    J = d / np.linalg.norm(d, axis=1)[:, None]
    return np.sqrt(np.diag(np.linalg.inv(J.T @ J)))


def best_pair_library(C: np.ndarray, X0: np.ndarray, tri: list[int]) -> tuple[int, int]:
    """The lesson's stand-in for ``best_pair`` while the student's blank is empty: the two
    points of ``C`` (n, 3) m not in ``tri`` whose ranges, added to those of ``tri``, give the
    station ``X0`` (3,) m the smallest σ_Z (never shown in the lesson, so that the pair is
    not printed before the student answers; :func:`check_steep_pair` refuses it)."""
    free = [k for k in range(len(C)) if k not in tri]
    pairs = [(a, b) for n, a in enumerate(free) for b in free[n + 1 :]]
    return min(pairs, key=lambda pr: float(_station_sigma(C, X0, list(tri) + list(pr))[2]))


_NO_TRIAL = {
    **INVERTERS,
    "np.linalg.det": np.linalg.det,
    "np.linalg.eig": np.linalg.eig,
    "np.linalg.eigh": np.linalg.eigh,
    "np.linalg.svd": np.linalg.svd,
    "np.linalg.cond": np.linalg.cond,
}


@own_work(
    "that is the stand-in, a search over all pairs; the exercise is a rule you reason out",
    best_pair_library=best_pair_library,
)
@small_matrices(
    0,
    "this exercise asks for a geometric rule, not a trial of the pairs' precision — which rays "
    "fix a height?",
    **_NO_TRIAL,
)
def check_steep_pair(fn: Callable) -> None:
    """Check ``fn(C, X0, tri) -> (i, j)``: two points (not in ``tri``) chosen by a geometric rule
    — no matrix inverse, determinant or decomposition — whose ranges, added to those of ``tri``,
    give the station a σ_Z within 10 % of the best pair's.

    Oracle: every pair tried, σ from (JᵀJ)⁻¹ with J the unit vectors station − point, on two
    scenes the student has not seen (a station 12 km above 20 points spread over ±40 km).
    """
    for salt in (0, 2):  # scene 2: the 3-D criterion (trace of (JᵀJ)⁻¹) is 23 % worse in σ_Z
        rng = rng_for("lesson14.check_best_pair", salt)
        C = np.column_stack([rng.uniform(-40e3, 40e3, 20), rng.uniform(-40e3, 40e3, 20),
                             rng.uniform(-600.0, 600.0, 20)])  # fmt: skip
        X0 = np.array([3000.0, -2000.0, 12000.0])
        far = np.argsort(-np.hypot(*(C[:, :2] - X0[:2]).T))
        tri = sorted(int(k) for k in far[[0, 2, 5]])
        pairs = [
            (a, b) for a in range(20) for b in range(a + 1, 20) if a not in tri and b not in tri
        ]
        sig = {pr: _station_sigma(C, X0, tri + list(pr)) for pr in pairs}
        best = min(pairs, key=lambda pr: sig[pr][2])
        got = call(fn, C.copy(), X0.copy(), list(tri), what="steep_pair")
        try:
            g = tuple(sorted(int(k) for k in got))
        except (TypeError, ValueError):
            raise CheckFailed(f"steep_pair: expected two point indices, got {got!r}") from None
        if len(g) != 2 or g[0] == g[1]:
            raise CheckFailed(f"steep_pair: expected two different point indices, got {got!r}")
        if g not in sig:
            raise CheckFailed(
                f"steep_pair: {g} — one of them is already among the three, or an index is out "
                "of range"
            )
        ratio = float(sig[g][2] / sig[best][2])
        if ratio <= 1.10:
            continue
        names = {
            max(pairs, key=lambda pr: np.linalg.norm(C[pr[0], :2] - C[pr[1], :2])): (
                "the two points farthest apart: spread helps the plan, the height needs steep "
                "rays"),
            min(pairs, key=lambda pr: np.hypot(*sig[pr][:2])): (
                "a pair good for the plan position; the question is the height"),
            min(pairs, key=lambda pr: np.sum(sig[pr] ** 2)): (
                "the pair best for the 3-D position (the trace); the question is the height alone"),
        }  # fmt: skip
        why = names.get(g, "which rays change most with the station's height?")
        raise CheckFailed(
            f"steep_pair: {g} gives σ_Z {sig[g][2]:.2f} range-σ, {ratio:.2f} times the best pair's "
            f"{sig[best][2]:.2f} — {why}",
            error=np.inf,
            tolerance=0.0,
        )
    success(
        "σ_Z of the station within 10 % of the best pair in two scenes, by a rule without trials"
    )
