"""Checkers for lesson 15, debugging an adjustment someone hands you.

Oracles: residual fields built from known shift, scale and rotation; pixel coordinates
built backwards from chosen photo coordinates; scipy's χ² quantiles; RMS values computed
image by image in a plain loop — never the library's ``read_colmap``, ``image_table`` or
report functions.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.stats import chi2

from orientviz.adjust import gauss_newton
from orientviz.exercises._common import (
    CheckFailed,
    NotWrittenError,
    call,
    compare,
    own_work,
    rng_for,
    success,
)
from orientviz.exercises.sliders import answer_value


def check_residual_pattern(fn: Callable) -> None:
    """Check ``fn(xy, v) -> (shift (2,), scale, rotation)`` for v = t + λ·xy + ρ·(−y, x)."""
    rng = rng_for("lesson15.check_residual_pattern")
    for t, lam, rho in (([0.012, -0.031], 0.004, 0.0021), ([-0.2, 0.05], -1.99, -0.0007)):
        xy = rng.uniform(-110, 110, (15, 2))
        v = np.asarray(t) + lam * xy + rho * np.column_stack([-xy[:, 1], xy[:, 0]])
        with own_work(gauss_newton=gauss_newton):
            out = call(fn, xy.copy(), v.copy(), what="residual_pattern")
        try:
            shift, scale, rot = out
            got = np.r_[np.asarray(shift, float).ravel(), float(scale), float(rot)]
        except (TypeError, ValueError):
            raise CheckFailed("return (shift (2,), scale, rotation)") from None
        want = np.r_[t, lam, rho]
        compare(
            "(shift x, shift y, scale, rotation)",
            got,
            want,
            rtol=1e-9,
            scale=1.0,
            wrong=[
                (
                    "the rotation has the wrong sign: (−y, x) is a positive turn",
                    np.r_[t, lam, -rho],
                ),
                ("scale and rotation swapped", np.r_[t, rho, lam]),
            ],
        )
    success("shift, scale and rotation of two residual fields recovered exactly")


def check_colmap_to_photo(fn: Callable) -> None:
    """Check ``fn(uv, cx, cy, pixel_mm) -> xy``: COLMAP pixels to photo coordinates in mm."""
    rng = rng_for("lesson15.check_colmap_to_photo")
    cx, cy, p = 2011.4, 1498.7, 0.0052
    xy = rng.uniform(-10.0, 10.0, (8, 2))  # mm, y up
    uv = np.column_stack(
        [cx + xy[:, 0] / p, cy - xy[:, 1] / p]
    )  # built backwards: v grows downwards
    got = call(fn, uv.copy(), cx, cy, p, what="colmap_to_photo")
    compare(
        "photo coordinates [mm]",
        got,
        xy,
        rtol=1e-10,
        scale=10.0,
        wrong=[
            ("y is not flipped: COLMAP's v grows downwards, photo y upwards", xy * [1, -1]),
            ("cx and cy swapped", np.column_stack([(uv[:, 0] - cy) * p, -(uv[:, 1] - cx) * p])),
            (
                "divided by the pixel size instead of multiplied",
                np.column_stack([(uv[:, 0] - cx) / p, -(uv[:, 1] - cy) / p]),
            ),
        ],
    )
    success("pixels → mm with the principal point, the pixel size and y upwards")


def _first_r(accept_hi, ratio: float, lo: int = 1, hi: int = 10**6) -> int:
    """Smallest r in [lo, hi] with ``accept_hi(r) < ratio`` (the bound falls with r): bisection."""
    if accept_hi(hi) >= ratio:
        return hi
    while lo < hi:
        mid = (lo + hi) // 2
        if accept_hi(mid) < ratio:
            hi = mid
        else:
            lo = mid + 1
    return lo


def check_smallest_redundancy(fn: Callable) -> None:
    """Check ``fn(ratio, alpha) -> r``: the smallest redundancy at which the two-sided χ² test
    at level α rejects σ̂0 = ratio (> 1), i.e. ratio lies above the upper bound
    √(χ²_{1−α/2}(r)/r)."""
    cases = ((1.15, 0.05), (1.5, 0.05), (1.05, 0.01))
    for ratio, alpha in cases:
        upper = lambda r, a=alpha: float(np.sqrt(chi2.isf(a / 2, r) / r))  # noqa: E731
        want = _first_r(upper, ratio)
        got = call(fn, ratio, alpha, what="smallest_redundancy")
        try:
            got = float(got)
        except (TypeError, ValueError):
            raise CheckFailed("smallest_redundancy: return one integer, the redundancy r") from None
        one_sided = _first_r(lambda r, a=alpha: float(np.sqrt(chi2.isf(a, r) / r)), ratio)
        squared = _first_r(lambda r, a=alpha: float(chi2.isf(a / 2, r) / r), ratio)
        compare(f"r for σ̂0/σ0 = {ratio}, α = {alpha}", got, float(want), rtol=1e-12, scale=1.0, wrong=[
            ("one-sided: the two-sided test puts α/2 in the upper tail", float(one_sided)),
            ("this is the bound for σ̂0², compare σ̂0 = ratio with √(χ²/r)", float(squared)),
            ("one less than the first redundancy that rejects (off by one)", float(want - 1)),
        ])  # fmt: skip
    success(
        "a 15 % optimistic σ needs r ≥ "
        f"{_first_r(lambda r: float(np.sqrt(chi2.isf(0.025, r) / r)), 1.15)} before the test sees it"
    )


def expected_rms_library(image: np.ndarray, sigma: np.ndarray, r: np.ndarray, m: int) -> np.ndarray:
    """The lesson's stand-in for ``expected_rms`` while the student's blank is empty: per
    image (``m`` of them) and axis, the RMS (mm) the residuals of the rays ``image`` (n,)
    with σ ``sigma`` (n, 2, mm) and redundancy numbers ``r`` (n, 2) should show (never shown
    in the lesson; :func:`check_expected_rms` refuses it)."""
    image = np.asarray(image)
    var = np.asarray(sigma, float) ** 2 * np.asarray(r, float)
    total = np.zeros((m, 2))
    np.add.at(total, image, var)
    return np.sqrt(total / np.bincount(image, minlength=m)[:, None])


@own_work(
    "that is the stand-in; the exercise is the residual's variance worked out from Q_vv",
    expected_rms_library=expected_rms_library,
)
def check_expected_rms(fn: Callable) -> None:
    """Check ``fn(image, sigma, r, m) -> (m, 2)``: the RMS of the x and the y residuals each
    image should have if the a-priori σ are right, from the σ (n, 2) and the redundancy numbers
    r (n, 2) of its n rays: √(mean σ² r) per image and axis.

    Oracle: a small linear adjustment (random design, unequal σ) whose residual variances
    σ_v² = diag(Q_ll − A N⁻¹ Aᵀ) are computed here from the design — the student's function
    only gets σ and r. The lesson's stand-in :func:`expected_rms_library` is refused.
    """
    rng = rng_for("lesson15.check_expected_rms")
    n, u, m = 40, 7, 4
    image = np.repeat(np.arange(m), n // m)
    sigma = rng.uniform(0.003, 0.009, (n, 2))
    A = rng.normal(size=(2 * n, u))
    s = sigma.reshape(-1)
    N = A.T @ (A / s[:, None] ** 2)
    var_v = s**2 - np.einsum("ij,jk,ik->i", A, np.linalg.inv(N), A)  # diag(Q_ll − A N⁻¹ Aᵀ)
    r = (var_v / s**2).reshape(n, 2)
    want = np.array([[np.sqrt(np.mean(var_v.reshape(n, 2)[image == i, k])) for k in range(2)]
                     for i in range(m)])  # fmt: skip
    got = call(fn, image.copy(), sigma.copy(), r.copy(), m, what="expected_rms")
    sig_rms = np.array(
        [[np.sqrt(np.mean(sigma[image == i, k] ** 2)) for k in range(2)] for i in range(m)]
    )
    compare("expected RMS per image [mm]", got, want, rtol=1e-9, wrong=[
        ("the σ of the observations: a residual is smaller than its observation's error, "
         "σ_v = σ √r", sig_rms),
        ("the square root is missing: E(v²) = σ² r, the RMS is its root", want**2),
        ("r enters squared: σ_v² = σ² r, so σ_v = σ √r", np.array(
            [[np.sqrt(np.mean((sigma * r)[image == i, k] ** 2)) for k in range(2)] for i in range(m)])),
    ])  # fmt: skip
    success("the expected RMS per image and axis is √(mean σ² r)")


def check_false_alarms(
    answer: object,
    clean: Callable[[float], set],
    blunders: set,
    levels: tuple[float, ...] = (0.01, 0.1, 1.0, 5.0),
) -> None:
    """The number of good rays thrown out at the first level α0 (%, the lesson's slider
    positions, in increasing order) at which data snooping finds more of the planted
    ``blunders`` than at the smallest level.

    ``clean(alpha0_percent)`` returns the set of eliminated ray labels; the check runs it at
    every level itself (the library's data snooping is the oracle of what is eliminated; the
    counting is done here).
    """
    what = "false alarms where one more blunder is found"
    got = answer_value(answer, what)
    if got is None:
        raise NotWrittenError(f"{what}: not written yet (type the number you read off the slider)")
    runs = {a: clean(a) for a in levels}
    found = {a: len(runs[a] & blunders) for a in levels}
    level = next((a for a in levels if found[a] > found[levels[0]]), None)
    if level is None:  # pragma: no cover - the lesson's block has one
        raise CheckFailed(f"{what}: no level finds more blunders than α0 = {levels[0]} %")
    want = len(runs[level] - blunders)
    if got == want:
        success(f"at α0 = {level:g} % {found[level]} of the {len(blunders)} blunders are found, "
                f"and {want} good rays are thrown out with them")  # fmt: skip
        return
    wrong = {len(runs[level]): "all rays eliminated there; a false alarm is one that is no blunder"}
    wrong.setdefault(found[level], "the blunders found, not the false alarms")
    for a in levels:
        if a != level:
            wrong.setdefault(len(runs[a] - blunders), f"the false alarms at α0 = {a:g} %")
    why = wrong.get(int(got), f"read the line at α0 = {level:g} % again")
    raise CheckFailed(f"{what}: {got:g} — {why}", error=np.inf, tolerance=0.0)
