"""Checkers for lesson 16, network design: the block's precision before it is flown.

Oracles: the inverse of the enlarged normal matrix formed from scratch (for the update of
the cofactors and for the best candidate), the flight geometry written out (for the
accuracy law's σ0), and the bundle adjustment of the design block with the student's
control points made control (for the control placed by hand) — never the studio's
update formula (:class:`orientviz.design.LiveDesign`) or its suggestion.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..block import CONTROL
from ..bundle import bundle_adjust
from ..simulate import simulate_block
from ._common import INVERTERS, CheckFailed, call, compare, rng_for, small_matrices, success
from .sliders import check_slider_answer, crossing

#: The design of the by-hand exercise: 3 strips × 9 images at 1 : 10 000, wide angle,
#: 60 % / 20 % overlap, flat terrain, XYZ control at the 4 corners (σ 2 cm), image σ 5 µm.
TASK: dict[str, Any] = {
    "strips": 3,
    "images_per_strip": 9,
    "control": "corners",
    "sigma_control": 0.02,
    "sigma_image_mm": 0.005,
}
#: The required largest σ_Z of the non-control points, m.
TARGET_SIGMA_Z: float = 0.35
#: The fewest added control points that reach the target: one is not enough (the check
#: tries every point), two are (tests/exercises/test_lesson16.py computes a pair that does).
FEWEST: int = 2


def _design_block():
    """The task's design block: planned geometry, weighted control (no random errors)."""
    sim = simulate_block(
        TASK["strips"], TASK["images_per_strip"], rng=np.random.default_rng(0), relief=0.0,
        extra=None, control=TASK["control"], control_sigma=TASK["sigma_control"],
        sigma_image_mm=TASK["sigma_image_mm"], start_error=None,
        flight_jitter=(0.0, 0.0, 0.0, 0.0),
    )  # fmt: skip
    return sim.truth.copy()


def worst_sigma_z(block, control_ids: Sequence[str], sigma: float = 0.02) -> float:
    """Largest σ_Z (m) of the non-control points with ``control_ids`` made XYZ control.

    The bundle adjustment of the design block (error-free observations, a-priori σ0 = 1,
    weighted control) with its precision: the design's σ.
    """
    b = block.copy()
    ids = b.points.ids
    for name in control_ids:
        j = ids.index(name)
        b.points.sigma[j] = sigma
        b.points.xyz_known[j] = b.points.xyz[j]
        b.points.role[j] = CONTROL
    res = bundle_adjust(b, control="weighted", precision=True, max_iter=2)
    Qp = np.asarray(res.cofactor_groups["points"])
    sz = np.sqrt(np.clip(Qp[:, 2, 2], 0.0, None))
    return float(sz[b.points.role != CONTROL].max())


@small_matrices(
    3,
    "a new u × u inverse, as the stand-in control_update_library computes it; the Woodbury "
    "update inverts only the 3 × 3 matrix P⁻¹ + Q_jj of the new control point",
    **INVERTERS,
)
def check_control_update(fn: Callable) -> None:
    """Check ``fn(Q, idx, sigma) -> Q_new``: the cofactors after making a point control.

    ``Q`` (u, u) is the cofactor matrix of the design, ``idx`` the three indices of the
    point's X, Y, Z among the unknowns, ``sigma`` (3,) the σ of the given coordinates (m).
    The answer may invert or solve with matrices of at most 3 × 3 (numpy's and scipy's
    inverses and solvers are watched): the exercise is the update without a new inverse.
    """
    rng = rng_for("lesson16.check_control_update")
    for u, idx, sigma in ((11, [7, 2, 9], [0.03, 0.05, 0.02]), (8, [0, 1, 2], [0.4, 0.1, 0.25])):
        A = rng.normal(size=(3 * u, u))
        N = A.T @ np.diag(rng.uniform(0.5, 3.0, 3 * u)) @ A
        Q = np.linalg.inv(N)
        s = np.asarray(sigma)
        E = np.zeros((3, u))
        E[np.arange(3), idx] = 1.0
        ref = np.linalg.inv(N + E.T @ np.diag(1 / s**2) @ E)  # oracle: the enlarged N inverted
        got = call(fn, Q.copy(), list(idx), s.copy(), what="control_update")
        Qj = Q[:, idx]
        Qjj = Q[np.ix_(idx, idx)]
        compare(
            f"Q' (u = {u})",
            got,
            ref,
            rtol=1e-8,
            wrong=[
                (
                    "(P + Q_jj)⁻¹ with P = 1/σ²: the inner matrix needs P⁻¹ = σ²",
                    Q - Qj @ np.linalg.inv(np.diag(1 / s**2) + Qjj) @ Qj.T,
                ),
                (
                    "σ instead of σ² in P⁻¹",
                    Q - Qj @ np.linalg.inv(np.diag(s) + Qjj) @ Qj.T,
                ),
                (
                    "the sign: new control makes the cofactors smaller (Q − …)",
                    Q + Qj @ np.linalg.inv(np.diag(s**2) + Qjj) @ Qj.T,
                ),
            ],
        )
    success("Q' equals the inverse of N + AᵀPA: one 3×3 inverse instead of a new u×u one")


def _law_sigma_z(sigma_img_mm: float, scale: float, c_mm: float, fmt: float, p: float,
                 mu_i: float) -> float:  # fmt: skip
    """μ_z(i)·σ0z (m) of a flight at the image scale number ``scale``, H and B written out."""
    H = c_mm * 1e-3 * scale
    base = fmt * 1e-3 * scale * (1 - p)
    return mu_i * np.sqrt(2.0) * sigma_img_mm * 1e-3 * scale * H / base


def check_largest_scale(fn: Callable) -> None:
    """Check ``fn(sigma_img_mm, c_mm, format_mm, p, target_m, mu_i) -> scale``: the largest image
    scale number m_B at which Ebner's height law μ_z(i)·σ0z, σ0z = √2 σ_x m_B H/B, still meets
    the target (m), for one chain spacing (μ_z(i) given).

    Oracle: the law evaluated with H = c m_B and B = (1 − p)·format·m_B written out, and a
    bisection over m_B — not the closed form.
    """
    for sigma_img, c_mm, fmt, p, target, mu_i in (
        (0.005, 152.0, 230.0, 0.6, 0.15, 1.42),
        (0.008, 88.0, 230.0, 0.65, 0.5, 2.07),
    ):
        lo, hi = 1.0, 1e7
        for _ in range(200):  # the law grows with the scale number: bisection
            mid = np.sqrt(lo * hi)
            if _law_sigma_z(sigma_img, mid, c_mm, fmt, p, mu_i) <= target:
                lo = mid
            else:
                hi = mid
        want = lo
        got = call(fn, sigma_img, c_mm, fmt, p, target, mu_i, what="largest_scale")
        try:
            got = float(got)
        except (TypeError, ValueError):
            raise CheckFailed(f"largest_scale: expected one number m_B, got {got!r}") from None
        hb = c_mm / ((1 - p) * fmt)  # H/B, the same at every scale
        compare(f"m_B for σ_Z ≤ {target} m (σ_x {sigma_img * 1000:g} µm, c {c_mm:g} mm)", got, want,
                rtol=1e-6, wrong=[
                    ("the base uses p, not 1 − p: B = (1 − p)·format·m_B", want * p / (1 - p)),
                    ("√2 is missing: σ0z is the σ of a model height from the x-parallax of TWO "
                     "image coordinates", want * np.sqrt(2.0)),
                    ("H/B does not grow with the scale: H = c m_B and B = (1 − p) s m_B, so H/B = "
                     "c/((1 − p) s) and σ0z is LINEAR in m_B",
                     np.sqrt(target / (mu_i * np.sqrt(2.0) * sigma_img * 1e-3 * hb) * 1.0)),
                    ("μ_z(i) left out: the law is μ_z(i)·σ0z, not σ0z", want * mu_i),
                    ("H/B upside down", target / (mu_i * np.sqrt(2.0) * sigma_img * 1e-3 / hb)),
                ])  # fmt: skip
    success("the largest image scale number that keeps the law's σ_Z at the target, two flights")


def check_by_hand(fn: Callable) -> None:
    """Check ``fn() -> list of point ids``: the fewest extra control points with which the
    task's design (:data:`TASK`) reaches σ_Z ≤ :data:`TARGET_SIGMA_Z` everywhere."""
    ids = call(fn, what="my_control_points")
    if isinstance(ids, str) or not all(isinstance(x, str) for x in ids):
        raise CheckFailed("return a list of point ids such as ['g02_004', …]")
    block = _design_block()
    unknown = [x for x in ids if x not in block.points.ids]
    if unknown:
        raise CheckFailed(f"no point {unknown[0]!r} in the design (ids look like 'g02_004')")
    got = worst_sigma_z(block, list(ids))
    if got > TARGET_SIGMA_Z * (1 + 1e-6):
        raise CheckFailed(
            f"with {len(ids)} added control points the largest σ_Z is {got:.3f} m, above the "
            f"required {TARGET_SIGMA_Z} m — put control where σ_Z is largest (colour by σ_Z)",
            error=(got - TARGET_SIGMA_Z) / TARGET_SIGMA_Z,
            tolerance=1e-6,
        )
    # the fewest: one point is not enough (every one tried here), FEWEST are
    tie = [x for j, x in enumerate(block.points.ids) if block.points.role[j] != CONTROL]
    best_one = min(worst_sigma_z(block, [x]) for x in tie)
    fewest = 1 if best_one <= TARGET_SIGMA_Z else FEWEST
    if len(set(ids)) > fewest:
        raise CheckFailed(
            f"{len(set(ids))} points reach σ_Z {got:.3f} m, but {fewest} are enough (one alone "
            f"leaves at best {best_one:.2f} m): look for a better placement"
        )
    success(
        f"{len(set(ids))} added control points: largest σ_Z {got:.3f} m ≤ {TARGET_SIGMA_Z} m "
        f"(the best single point leaves {best_one:.2f} m)"
    )


def _worst_after(Q: np.ndarray, j: int, sigma: float) -> float:
    """Largest σ_Z (m) of the points other than ``j`` after making ``j`` control — by the
    inverse of the enlarged normal matrix (the oracle)."""
    u = Q.shape[0]
    E = np.zeros((3, u))
    E[np.arange(3), [3 * j, 3 * j + 1, 3 * j + 2]] = 1.0
    Qn = np.linalg.inv(np.linalg.inv(Q) + E.T @ E / sigma**2)
    sz = np.sqrt(np.diag(Qn)[2::3])
    return float(np.delete(sz, j).max())


def _candidate_case(rng: np.random.Generator, p: int) -> tuple[np.ndarray, list[int]]:
    """Point cofactors (3p × 3p) of a chain of points tied to their neighbours, and the
    candidates, drawn until the point with the largest σ_Z is *not* the best candidate."""
    while True:
        A = np.zeros((0, 3 * p))
        for k in range(p - 1):  # coordinate differences of neighbours, random weights
            D = np.zeros((3, 3 * p))
            D[:, 3 * k : 3 * k + 3] = -np.eye(3)
            D[:, 3 * k + 3 : 3 * k + 6] = np.eye(3) + 0.3 * rng.normal(size=(3, 3))
            A = np.vstack([A, D * rng.uniform(0.5, 3.0)])
        E0 = np.zeros((3, 3 * p))
        E0[:, :3] = np.eye(3)  # the first point is control
        N = A.T @ A + E0.T @ E0 * 1e4 + 1e-3 * np.eye(3 * p)
        Q = np.linalg.inv(N)
        cand = sorted(rng.choice(np.arange(1, p), size=min(6, p - 1), replace=False).tolist())
        worst = [_worst_after(Q, j, 0.05) for j in cand]
        sz = np.sqrt(np.diag(Q)[2::3])
        if cand[int(np.argmax(sz[cand]))] != cand[int(np.argmin(worst))]:
            return Q, cand


def _after(Q: np.ndarray, j: int, sigma: float) -> np.ndarray:
    """σ_Z (m) of every point after making ``j`` control — by the inverse of the enlarged normal
    matrix (the oracle)."""
    u = Q.shape[0]
    E = np.zeros((3, u))
    E[np.arange(3), [3 * j, 3 * j + 1, 3 * j + 2]] = 1.0
    return np.sqrt(np.diag(np.linalg.inv(np.linalg.inv(Q) + E.T @ E / sigma**2))[2::3])


def check_after_worst(fn: Callable) -> None:
    """Check ``fn(Q, sigma) -> (k, sigma_z)``: make the point with the largest σ_Z control (XYZ,
    σ ``sigma`` m); return the point whose σ_Z is then the largest of the others, and that σ_Z (m).

    ``Q`` (3p, 3p) are the cofactors of the points' coordinates (X, Y, Z of point 0, …). Oracle:
    the inverse of the enlarged normal matrix, on chains of points drawn so that the worst point
    is not the best place for control.
    """
    rng = rng_for("lesson16.check_after_worst")
    cases = [_candidate_case(rng, 9), _candidate_case(rng, 12)]
    for Q, _ in cases:
        sz = np.sqrt(np.diag(Q)[2::3])
        j = int(np.argmax(sz))
        after = _after(Q, j, 0.05)
        others = np.delete(np.arange(len(sz)), j)
        k = int(others[np.argmax(after[others])])
        got = call(fn, Q.copy(), 0.05, what="after_worst")
        try:
            gk, gs = int(got[0]), float(got[1])
        except (TypeError, ValueError, IndexError):
            raise CheckFailed("after_worst: return (point index, σ_Z in m)") from None
        if gk == j:
            raise CheckFailed(
                f"after_worst: point {gk} is the one made control — the question is where the "
                "block is worst AFTERWARDS, among the other points"
            )
        if gk != k:
            second = int(others[np.argmax(sz[others])])
            why = (
                " — that was the second worst BEFORE; the update changes the others too, "
                "each by its covariance with the new control point"
                if gk == second
                else ""
            )
            raise CheckFailed(
                f"after_worst: point {gk} has σ_Z {after[gk]:.4f} m afterwards, point {k} "
                f"{after[k]:.4f} m{why}"
            )
        compare(
            "σ_Z of the worst point afterwards [m]",
            gs,
            after[k],
            rtol=1e-6,
            wrong=[
                ("this is its variance σ_Z² (m²): take the square root", after[k] ** 2),
                ("this is its σ_Z BEFORE the control point was added: update Q first",
                 sz[k]),
            ],
        )  # fmt: skip
    success("the worst spot after control at the worst point: found, with its σ_Z")


__all__ = [
    "FEWEST",
    "TARGET_SIGMA_Z",
    "TASK",
    "check_after_worst",
    "check_by_hand",
    "check_control_update",
    "check_largest_scale",
    "worst_sigma_z",
]


def _largest_other_sz(Q: np.ndarray, j: int, sigma: float) -> float:
    """Largest σ_Z (m) of the points other than j after point j becomes XYZ control with σ
    (m): the enlarged normal matrix inverted from scratch (Q: cofactors of all points, m²)."""
    E = np.zeros((3, len(Q)))
    E[[0, 1, 2], [3 * j, 3 * j + 1, 3 * j + 2]] = 1.0
    Qn = np.linalg.inv(np.linalg.inv(Q) + E.T @ E / sigma**2)
    return float(np.delete(np.sqrt(np.diag(Qn)[2::3]), j).max())


def check_control_sigma(
    answer: object, Q: np.ndarray, j: int, worse: float = 0.10, step: float = 0.02
) -> None:
    """The σ (m) of the given coordinates of control point ``j`` at which the largest σ_Z of
    the other points is ``worse`` (10 %) above what an error-free control point there gives
    (the lesson's slider, ``step`` m).

    Oracle: the normal matrix N = Q⁻¹ enlarged by the point's three weighted rows and
    inverted whole, bisected in σ — not the Woodbury update of the lesson or the studio.
    """
    perfect = _largest_other_sz(Q, j, 1e-6)
    want = crossing(lambda s: _largest_other_sz(Q, j, s), (1 + worse) * perfect, 1e-4, 20.0, 60)
    own = float(np.sqrt(Q[3 * j + 2, 3 * j + 2]))
    wrong = [
        ("the largest σ_Z itself, not the control's σ that causes it", (1 + worse) * perfect),
        ("the point's own σ_Z before it became control", own),
        ("in cm, not m", want * 100.0),
    ]  # fmt: skip
    check_slider_answer("σ of the control point", answer, want, step, "m", wrong)
