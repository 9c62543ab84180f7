"""Checkers for lesson 08, block triangulation.

The own independent-model adjustment (its partial derivatives and the whole iteration) is
checked in :mod:`._independent_models`, re-exported here. Oracles of the other checks:
error-free simulated truth (a similarity, a logarithmic law with known parameters) and σ0
written out by hand; never the library's ``similarity_transform``, ``polynomial_adjust`` or
``fit_log_law``. The degree of the strip polynomial: the checker's own real-valued fit and
``scipy.stats.chi2``. The n-ray intersection: error-free rays (they meet in the truth), two
rays built around a known common perpendicular (the midpoint), and scipy's minimiser of the
perpendicular distances for noisy rays.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.optimize import least_squares

from ..orientation.absolute import similarity_closed_form  # forbidden inside the student's
from ..orientation.intersection import intersect_points, intersect_rays  # functions, no oracle
from ._common import (
    CheckFailed,
    call,
    check_determined_table,
    compare,
    own_work,
    rng_for,
    success,
)
from ._independent_models import (  # the student's own block method
    check_adjust_models,
    check_model_jacobian,
    model_jacobian_numeric,
)
from ._polynomial_strip import check_strip_polynomial  # the student's polynomial method

__all__ = [
    "check_adjust_models",
    "check_compose",
    "check_strip_degree",
    "check_determined",
    "check_intersect_many",
    "check_model_jacobian",
    "check_strip_polynomial",
    "check_strips_for",
    "model_jacobian_numeric",
]


def _rodrigues(axis, angle: float) -> np.ndarray:
    """Rotation by ``angle`` (rad) about ``axis``, written out (not the library's)."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _similarity_cases(rng: np.random.Generator):
    """Two error-free cases: a hilly model and a flat one (all model z equal)."""
    x1 = rng.uniform(-100, 100, (6, 3)) * [1.0, 0.8, 0.15] + [0, 0, -150]
    x2 = np.column_stack([rng.uniform(-90, 90, 8), rng.uniform(-80, 80, 8), np.full(8, -152.0)])
    cases = []
    for x, axis, ang, s, t in (
        (x1, [0.3, -0.5, 0.8], 0.41, 7.3, [4520.0, 1870.0, 960.0]),
        (x2, [-0.2, 0.1, 1.0], 2.2, 9.85, [-310.0, 5400.0, 1520.0]),
    ):
        R = _rodrigues(axis, ang)
        cases.append((x, t + s * x @ R.T, s, R, np.array(t)))
    return cases


def _triple(out) -> tuple[float, np.ndarray, np.ndarray]:
    try:
        s_hat, R_hat, t_hat = out
        return float(s_hat), np.asarray(R_hat, float), np.asarray(t_hat, float)
    except (TypeError, ValueError):
        raise CheckFailed("return the three values (scale, R, t)") from None


@own_work(similarity_closed_form=similarity_closed_form)
def check_compose(fn: Callable) -> None:
    """Check ``fn(s1, s2) -> (scale, R, t)``: the similarity that applies s2 first, then s1
    (each ``(scale, R, t)`` maps x to scale · R · x + t) — chaining a model into its
    predecessor's frame."""
    rng = np.random.default_rng(808)
    ang = rng.uniform(-0.3, 0.3, (2, 3))
    s1 = (1.07, _rodrigues([1, 0, 0], ang[0, 0]) @ _rodrigues([0, 1, 0], ang[0, 1]) @ _rodrigues([0, 0, 1], ang[0, 2]),
          np.array([120.0, -40.0, 15.0]))  # fmt: skip
    s2 = (0.93, _rodrigues([0, 0, 1], ang[1, 2]) @ _rodrigues([1, 0, 0], ang[1, 0]) @ _rodrigues([0, 1, 0], ang[1, 1]),
          np.array([-35.0, 60.0, 4.0]))  # fmt: skip
    m, R, t = _triple(call(fn, s1, s2, what="compose"))
    # oracle: the two transformations applied one after the other to four points
    pts = rng.normal(0.0, 50.0, (4, 3))
    want = s1[0] * (s2[0] * pts @ s2[1].T + s2[2]) @ s1[1].T + s1[2]
    if R.shape != (3, 3) or t.shape != (3,):
        raise CheckFailed(f"compose: R must be 3 × 3 and t of length 3 (got {R.shape}, {t.shape})")
    got = m * pts @ R.T + t
    other = s2[0] * (s1[0] * pts @ s1[1].T + s1[2]) @ s2[1].T + s2[2]
    no_scale_t = want - s1[0] * s2[2] @ s1[1].T + s2[2] @ s1[1].T
    no_rot_t = want - s1[0] * s2[2] @ s1[1].T + s1[0] * s2[2]
    compare("four points through your composed similarity", got, want, rtol=1e-9, wrong=[
        ("the order is wrong: s2 acts first, then s1 (s1 ∘ s2)", other),
        ("t = m1 R1 t2 + t1: the scale m1 is missing from the shift", no_scale_t),
        ("t = m1 R1 t2 + t1: the rotation R1 is missing from the shift", no_rot_t),
    ])  # fmt: skip
    compare("scale", m, s1[0] * s2[0], rtol=1e-12)
    success("s1 ∘ s2 moves four points as s2 followed by s1 does")


def _control_rank(x: np.ndarray, kinds: str) -> int:
    """Rank of the linearised 7-parameter similarity (tx, ty, tz, s, ω, φ, κ) of a level model
    (ω = φ = 0) with model points ``x`` (n, 3) and control ``kinds`` ("f" XYZ, "p" XY, "h" Z):
    central differences of the checker's own similarity, rank by singular values."""
    p0 = np.array([500.0, 300.0, 100.0, 8.0, 0.0, 0.0, 0.7])

    def f(p: np.ndarray) -> np.ndarray:
        R = _rodrigues([1, 0, 0], p[4]) @ _rodrigues([0, 1, 0], p[5]) @ _rodrigues([0, 0, 1], p[6])
        X = p[:3] + p[3] * x @ R.T
        rows = [
            X[i, :2] if k == "p" else X[i, 2:] if k == "h" else X[i] for i, k in enumerate(kinds)
        ]
        return np.concatenate(rows) if rows else np.zeros(0)

    if not kinds:
        return 0
    h = 1e-6
    A = np.column_stack([(f(p0 + e) - f(p0 - e)) / (2 * h) for e in np.eye(7) * h])
    sv = np.linalg.svd(A, compute_uv=False)
    return int(np.sum(sv > 1e-9 * sv[0]))


def check_determined(fn: Callable) -> None:
    """Check ``fn(n_full, n_plan, n_height) -> bool``: does that control (points in general
    position) determine the 7-parameter similarity of a level model of flat terrain?"""
    rng = np.random.default_rng(808)
    cases = [(f, p, h) for f in range(4) for p in range(5) for h in range(6)]
    truth, got = [], []
    for nf, npl, nh in cases:
        n = nf + npl + nh
        x = np.column_stack([rng.uniform(-90, 90, n), rng.uniform(-80, 80, n), np.full(n, -152.0)])
        truth.append(_control_rank(x, "f" * nf + "p" * npl + "h" * nh) == 7)
        answer = call(fn, nf, npl, nh, what="determined")
        if not isinstance(answer, (bool, np.bool_)):
            raise CheckFailed(f"determined{(nf, npl, nh)}: expected True or False, got {answer!r}")
        got.append(bool(answer))
    wrong_rules = [
        ("seven known coordinates are not enough: the X, Y equations and the Z equations "
         "fix different parameters (count plan and height separately)",
         lambda f, p, h: 3 * f + 2 * p + h >= 7),
        ("two height points leave the tilt about the line through them free: a plane needs "
         "three points with Z, not on one line", lambda f, p, h: f + p >= 2 and f + h >= 2),
        ("planimetric points fix the plan part as well as full points do",
         lambda f, p, h: f >= 2 and f + h >= 3),
        ("height points fix the height part as well as full points do",
         lambda f, p, h: f + p >= 2 and f >= 3),
        ("the scale and κ need two points with X, Y: one point fixes only the shift",
         lambda f, p, h: f + p >= 1 and f + h >= 3),
    ]  # fmt: skip
    check_determined_table(got, truth, cases, wrong_rules, labels="full, plan, height",
                           what="control", rank="the linearised similarity has rank 7")  # fmt: skip
    success(f"all {len(cases)} combinations of 0–3 full, 0–4 plan and 0–5 height points right")


def _conformal_residuals(xy: np.ndarray, XY: np.ndarray, degree: int) -> np.ndarray:
    """Residuals (2n,) m of X + iY = Σ c_k (x + iy)^k, fitted as a REAL least-squares problem
    (2 unknowns a_k, b_k per coefficient): the checker's own route, not the complex one."""
    z = xy[:, 0] + 1j * xy[:, 1]
    cols = []
    for k in range(degree + 1):
        p = z**k
        cols += [np.r_[p.real, p.imag], np.r_[-p.imag, p.real]]
    A = np.column_stack(cols)
    l = np.r_[XY[:, 0], XY[:, 1]]
    return A @ np.linalg.lstsq(A, l, rcond=None)[0] - l


def _strip_scene(seed: int, n: int, degree: int, noise: float, sigma: float = 0.05):
    """n control points on a strip 6 km × 1 km (strip coordinates in km), object XY in m from a
    conformal polynomial of ``degree`` bent by about 3 m, noise ``noise`` · σ."""
    rng = np.random.default_rng(seed)
    xy = np.column_stack([rng.uniform(0, 6, n), rng.uniform(-0.5, 0.5, n)])
    c = np.zeros(degree + 1, complex)
    c[0], c[1] = 3.0 + 2.0j, 1000.0 * np.exp(1j * rng.uniform(0, 6.3))  # m, m per km
    for k in range(2, degree + 1):
        c[k] = 3.0 * np.exp(1j * rng.uniform(0, 6.3)) / 6.0**k
    Z = np.polyval(c[::-1], xy[:, 0] + 1j * xy[:, 1])
    XY = np.column_stack([Z.real, Z.imag]) + rng.normal(0, noise * sigma, (n, 2))
    return xy, XY, sigma


def _degree_rules(s0: dict, r: dict, n: int, sigma: float) -> tuple[int, dict]:
    """The smallest degree the one-sided χ² test accepts, and the degrees the plausible wrong
    rules pick (diagnosis → degree), from σ̂0 and r of degrees 1 … 4."""
    from scipy.stats import chi2

    def bound(q: float, dof: int) -> float:
        return float(np.sqrt(chi2.ppf(q, dof) / dof))

    def first(ok) -> int:
        return next((d for d in s0 if ok(d)), 4)

    want = first(lambda d: s0[d] <= bound(0.95, r[d]))
    rules = {
        "count the redundancy in real numbers: n points give 2n equations (X and Y), a "
        "complex coefficient is 2 unknowns: r = 2n − 2(d + 1)":
            first(lambda d: s0[d] * np.sqrt(r[d] / (n - d - 1)) <= bound(0.95, n - d - 1)),
        "a σ̂0 below 1, even significantly, says the σ are pessimistic, not that the model is "
        "too weak: the test for a sufficient degree is one-sided (reject only a σ̂0 "
        "significantly too LARGE)":
            first(lambda d: bound(0.025, r[d]) <= s0[d] <= bound(0.975, r[d])),
        "σ̂0 > 1 is not a rejection: accept a degree unless σ̂0 exceeds the χ² bound "
        "√(χ²_{r,0.95}/r)": first(lambda d: s0[d] <= 1.0),
        "the SMALLEST accepted degree: a higher one always fits the control better, not "
        "necessarily the strip": min(s0, key=s0.get),
        "divide the residuals by σ (σ̂0 has no unit) before comparing with the χ² bound":
            first(lambda d: s0[d] * sigma <= bound(0.95, r[d])),
        "the test is at α = 5 %: σ̂0 against √(χ²_{r,0.95}/r), not at 10 %":
            first(lambda d: s0[d] <= bound(0.90, r[d])),
        "the test is at α = 5 %: σ̂0 against √(χ²_{r,0.95}/r), not at 2.5 %":
            first(lambda d: s0[d] <= bound(0.975, r[d])),
    }  # fmt: skip
    for t in (1.1, 1.2, 1.3, 1.4):
        rules[
            f"a fixed bound on σ̂0 (here {t}?) ignores the redundancy: the bound "
            "√(χ²_{r,0.95}/r) is 1.73 for r = 2 and 1.25 for r = 20"
        ] = first(lambda d, t=t: s0[d] <= t)
    return want, rules


#: (seed, control points, degree of the bend, noise in σ) of the check's strips, in the order
#: that lets each plausible wrong rule fail first where no other remaining rule picks its degree
#: (the fifth: σ̂0 1.37/1.44/1.375/1.31 for d = 1 … 4 at r = 12/10/8/6 — a fixed bound anywhere in
#: 1.1 … 1.4 and the levels 10 % and 2.5 % pick another degree than the 5 % test)
_STRIPS = ((7, 8, 3, 1.0), (0, 6, 2, 1.0), (3, 10, 2, 1.0), (3, 12, 3, 0.45), (26, 8, 1, 1.0))


def check_strip_degree(fn: Callable) -> None:
    """Check ``fn(xy, XY, sigma, max_degree) -> d``: the smallest degree 1 … max_degree of the
    conformal strip polynomial whose σ̂0 (control XY with σ in m, strip xy in km) is not
    significantly too large (one-sided χ² test, α = 5 %); max_degree if none is accepted.

    Oracle: the checker's real-valued fit (2 unknowns per complex coefficient) and
    ``scipy.stats.chi2`` on five simulated strips. A wrong degree is named by the wrong rule
    that picks it and was consistent with the answers on the strips before."""
    alive: set[str] | None = None
    for seed, n, true_degree, noise in _STRIPS:
        xy, XY, sigma = _strip_scene(seed, n, true_degree, noise)
        s0, r = {}, {}
        for d in range(1, 5):
            v = _conformal_residuals(xy, XY, d)
            r[d] = 2 * n - 2 * (d + 1)
            s0[d] = float(np.sqrt(v @ v / sigma**2 / r[d]))
        want, rules = _degree_rules(s0, r, n, sigma)
        alive = set(rules) if alive is None else alive
        got = call(fn, xy.copy(), XY.copy(), sigma, 4, what="strip_degree")
        try:
            k = int(got)
        except (TypeError, ValueError):
            raise CheckFailed(
                f"strip_degree: expected a degree (an integer), got {got!r}"
            ) from None
        if k == want:
            alive = {text for text in alive if rules[text] == k}
            continue
        named = [text for text in rules if text in alive and rules[text] == k]
        why = (
            " — or: ".join(named)
            if named
            else "fit each degree, then test σ̂0 against √(χ²_{r,0.95}/r)"
        )
        table = ", ".join(f"d = {d}: σ̂0 {s0[d]:.3f}" for d in s0)
        raise CheckFailed(
            f"strip_degree ({n} control points): {k}, expected {want} — {why}. The fits: {table}"
        )
    success("the smallest degree the one-sided χ² test accepts, on all five strips")


def check_strips_for(fn: Callable) -> None:
    """Check ``fn(a, b, mu_max) -> n_s``: the number of strips at which Ebner's line
    μ = a + b · log10(n_s) reaches ``mu_max`` (``inf`` if it never does, b ≤ 0)."""
    cases = [(0.62, 0.71, 2.0), (1.0, 0.2, 1.5), (0.93, 0.073, 2.0), (1.19, -0.10, 2.0)]
    for a, b, m in cases:
        got = call(fn, a, b, m, what="strips_for")
        try:
            n = float(got)
        except (TypeError, ValueError):
            raise CheckFailed(
                f"strips_for({a}, {b}, {m}): expected one number, got {got!r}"
            ) from None
        if b <= 0:
            if n != np.inf:
                raise CheckFailed(
                    f"strips_for({a}, {b}, {m}) = {n:.4g}: with b ≤ 0 the line never rises to "
                    f"{m} (μ does not grow with n_s) — return np.inf"
                )
            continue
        if not (np.isfinite(n) and n > 0):
            raise CheckFailed(
                f"strips_for({a}, {b}, {m}) = {n}: a number of strips is positive and finite here"
            )
        e = (m - a) / b  # log10 of the answer
        wrong = [
            ("the natural logarithm: the law is in log10 n_s, so n_s = 10^((μ − a)/b)",
             e * np.log10(np.e)),
            ("a is missing: solve a + b log10 n_s = μ_max, not b log10 n_s = μ_max", m / b),
        ]  # fmt: skip
        if e > 0:
            wrong.append(("this is log10 n_s, not n_s itself", np.log10(e)))
        compare(
            f"log10 of strips_for({a}, {b}, {m})",
            np.log10(n),
            e,
            rtol=1e-9,
            scale=max(1.0, abs(e)),
            wrong=wrong,
        )
    success("n_s = 10^((μ_max − a)/b), and never (∞) when the line does not rise")


def _project(X: np.ndarray, X0: np.ndarray, R: np.ndarray, c: float) -> np.ndarray:
    """Image coordinates (mm) of X seen from X0 with R (image → object), principal distance c."""
    uvw = R.T @ (X - X0)
    return -c * uvw[:2] / uvw[2]


def _rays_scene(rng: np.random.Generator, n: int):
    """n tilted images (about 1800 m up, κ anywhere) around a ground point P."""
    P = np.array([rng.uniform(-300, 300), rng.uniform(-300, 300), rng.uniform(100, 160)])
    X0 = P + np.column_stack(
        [rng.uniform(-600, 600, n), rng.uniform(-600, 600, n), rng.uniform(1600, 1900, n)]
    )
    R = np.stack(
        [
            _rodrigues([1, 0, 0], rng.uniform(-0.05, 0.05))
            @ _rodrigues([0, 1, 0], rng.uniform(-0.05, 0.05))
            @ _rodrigues([0, 0, 1], rng.uniform(-3, 3))
            for _ in range(n)
        ]
    )
    return P, X0, R


def _distances(
    X: np.ndarray, X0: np.ndarray, R: np.ndarray, xy: np.ndarray, c: float
) -> np.ndarray:
    """Perpendicular distance vectors (m) from X to each ray (flattened)."""
    d = np.einsum("nij,nj->ni", R, np.column_stack([xy, np.full(len(xy), -c)]))
    d /= np.linalg.norm(d, axis=1)[:, None]
    r = X - X0
    return (r - np.sum(r * d, axis=1)[:, None] * d).ravel()


@own_work(intersect_points=intersect_points, intersect_rays=intersect_rays)
def check_intersect_many(intersect_many: Callable) -> None:
    """``intersect_many(X0, R, xy, c)`` must return the point (3,) nearest to all n rays in the
    least-squares sense (the sum of squared perpendicular distances); X0 (n, 3) m, R (n, 3, 3)
    image → object, xy (n, 2) mm reduced to the principal point, c mm."""

    def _least_squares_point(X0, R, xy, c, normalise=True):
        """The point nearest to the rays, for naming wrong answers (R transposed, d not unit)."""
        d = np.einsum("nij,nj->ni", R, np.column_stack([xy, np.full(len(xy), -c)]))
        if normalise:
            d = d / np.linalg.norm(d, axis=1)[:, None]
        M = np.eye(3)[None] * np.sum(d * d, axis=1)[:, None, None] - d[:, :, None] * d[:, None, :]
        return np.linalg.solve(M.sum(0), np.einsum("nij,nj->i", M, X0))

    rng = rng_for("lesson08.check_intersect_many")
    c = 123.9
    # 1. error-free rays from four images meet in the point
    P, X0, R = _rays_scene(rng, 4)
    xy = np.array([_project(P, X0[i], R[i], c) for i in range(4)])
    got = call(intersect_many, X0.copy(), R.copy(), xy.copy(), c, what="intersect_many")
    wrong = []
    if np.shape(got) == (3,):
        Rt = np.transpose(R, (0, 2, 1))
        wrong = [("R transposed: the ray direction is R (x, y, −c), not Rᵀ (x, y, −c)",
                  _least_squares_point(X0, Rt, xy, c)),
                 ("the image vector is (x, y, +c): the image plane lies at z = −c",
                  _least_squares_point(X0, R, xy, -c))]  # fmt: skip
    compare("the point of four error-free rays [m]", got, P, rtol=1e-9, scale=1000.0, wrong=wrong)
    # 2. two rays with a known common perpendicular: the midpoint
    Pm, X0m, Rm = _rays_scene(rng, 2)
    xy_true = np.array([_project(Pm, X0m[i], Rm[i], c) for i in range(2)])
    d = np.einsum("nij,nj->ni", Rm, np.column_stack([xy_true, [-c, -c]]))
    nrm = np.cross(d[0], d[1])
    nrm /= np.linalg.norm(nrm)
    Q = np.array([Pm + 0.4 * nrm, Pm - 0.4 * nrm])  # 0.8 m gap, perpendicular to both rays
    X0m = X0m + np.array([0.4, -0.4])[:, None] * nrm  # the rays keep their directions, through Q
    xy2 = np.array([_project(Q[i], X0m[i], Rm[i], c) for i in range(2)])
    got = call(intersect_many, X0m.copy(), Rm.copy(), xy2.copy(), c, what="intersect_many")
    compare(
        "two rays 0.8 m apart: the midpoint of their common perpendicular [m]",
        got, Pm, rtol=1e-9, scale=1000.0,
        wrong=[
            ("this is the point on the first ray, not the midpoint", Q[0]),
            ("the directions are not normalised: longer direction vectors weigh more "
             "(divide d by its length)", _least_squares_point(X0m, Rm, xy2, c, normalise=False)),
        ],
    )  # fmt: skip
    # 3. five noisy rays of unequal length: scipy's minimiser of the perpendicular distances
    P5, X05, R5 = _rays_scene(rng, 5)
    X05[:, 2] += np.array([0.0, 900.0, -700.0, 300.0, 1500.0])  # very different ray lengths
    xy5 = np.array([_project(P5, X05[i], R5[i], c) for i in range(5)])
    xy5 += rng.normal(0, 0.02, xy5.shape)
    ref = least_squares(
        lambda X: _distances(X, X05, R5, xy5, c), P5 + 5.0, xtol=1e-15, ftol=1e-15, gtol=1e-15
    ).x
    got = call(intersect_many, X05.copy(), R5.copy(), xy5.copy(), c, what="intersect_many")
    wrong = [
        ("the directions are not normalised: longer direction vectors weigh more "
         "(divide d by its length)", _least_squares_point(X05, R5, xy5, c, normalise=False)),
        ("this is the mean of the pairwise midpoints, not the least-squares point of all rays",
         np.mean([_least_squares_point(X05[[i, k]], R5[[i, k]], xy5[[i, k]], c)
                  for i in range(5) for k in range(i + 1, 5)], axis=0)),
    ]  # fmt: skip
    compare("five noisy rays [m]", got, ref, rtol=1e-9, scale=1000.0, wrong=wrong)
    success(
        "intersect_many: error-free rays meet, two rays give the midpoint, n rays the point a "
        "minimiser of the perpendicular distances finds"
    )
