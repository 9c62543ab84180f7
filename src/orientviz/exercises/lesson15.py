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


def residual_pattern_library(xy: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, float, float]:
    """The lesson's stand-in for ``residual_pattern`` while the student's blank is empty: the
    4-parameter pattern (shift (2,) mm, scale, rotation rad) fitted to the misclosures ``w``
    (n, 2) mm at ``xy`` (n, 2) mm by the engine (kept here, not in the lesson, so that the blank's
    cell does not show the design matrix; :func:`check_residual_pattern` refuses it)."""
    A4 = np.zeros((2 * len(xy), 4))
    A4[0::2, 0], A4[1::2, 1] = 1.0, 1.0
    A4[0::2, 2], A4[1::2, 2] = xy[:, 0], xy[:, 1]
    A4[0::2, 3], A4[1::2, 3] = -xy[:, 1], xy[:, 0]
    p = gauss_newton(lambda q: (A4 @ q, A4), np.zeros(4), np.ravel(w), 0.005).x
    return p[:2], float(p[2]), float(p[3])


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


#: The three import mistakes of exercise 1 and the pattern labels a student chooses from.
IMPORT_CASES = (
    "v not flipped",
    "principal point at the image centre",
    "pixel size 0.012 mm instead of 0.010 mm",
)
PATTERNS = ("none", "shift", "scale", "rotation", "no pattern")


def _import_patterns() -> dict[str, tuple[str, str]]:
    """For each import mistake: the pattern label its misclosures show and why, from a
    vertical image imported wrongly (start values = the truth, so a correct import leaves
    no misclosure at all)."""
    rng = rng_for("lesson15.check_import_mistakes")
    f_px, p, W = 15200.0, 0.010, 23000.0  # principal distance in px, pixel size mm, format px
    cx, cy = W / 2 + 12.3, W / 2 - 11.1  # the principal point off the centre, px
    X = np.column_stack([rng.uniform(-700, 700, 30), rng.uniform(-700, 700, 30),
                         rng.uniform(-20, 20, 30)])  # fmt: skip
    X0 = np.array([15.0, -8.0, 1520.0])
    d = X - X0
    xy = -f_px * p * d[:, :2] / d[:, 2:3]  # true photo coordinates, mm from the pp (R = I)
    u, v = cx + xy[:, 0] / p, cy - xy[:, 1] / p  # COLMAP pixels, v downwards

    def misclosure(obs: np.ndarray, c: float) -> np.ndarray:
        return -c * d[:, :2] / d[:, 2:3] - obs  # computed (true start values) − observed

    wrong = {
        IMPORT_CASES[0]: misclosure(np.column_stack([(u - cx) * p, (v - cy) * p]), f_px * p),
        IMPORT_CASES[1]: misclosure(np.column_stack([(u - W / 2) * p, -(v - W / 2) * p]), f_px * p),
        IMPORT_CASES[2]: misclosure(
            np.column_stack([(u - cx) * 0.012, -(v - cy) * 0.012]), f_px * 0.012
        ),
    }
    out = {}
    for case, w in wrong.items():
        size = float(np.sqrt(np.mean(w**2)))
        if size < 1e-9:
            out[case] = ("none", "the misclosures are zero")
            continue
        A = np.zeros((2 * len(xy), 4))
        A[0::2, 0], A[1::2, 1] = 1.0, 1.0
        A[0::2, 2], A[1::2, 2] = xy[:, 0], xy[:, 1]
        A[0::2, 3], A[1::2, 3] = -xy[:, 1], xy[:, 0]
        q, *_ = np.linalg.lstsq(A, w.ravel(), rcond=None)
        rest = float(np.sqrt(np.mean((A @ q - w.ravel()) ** 2)))
        if rest > 0.1 * size:
            out[case] = ("no pattern", f"a pattern fit leaves {rest / size:.0%} of the misclosures")
            continue
        effect = {"shift": float(np.hypot(*q[:2])), "scale": abs(q[2]) * 100.0,
                  "rotation": abs(q[3]) * 100.0}  # fmt: skip
        label = max(effect, key=effect.get)
        out[case] = (label, f"shift {q[0] * 1000:+.0f}, {q[1] * 1000:+.0f} µm, scale {q[2]:+.2e}, "
                            f"rotation {q[3]:+.2e}")  # fmt: skip
    return out


_HINT = {
    IMPORT_CASES[0]: (
        "(v) What does a y axis that points the wrong way do to the picture — can a shift, a "
        "scale or a turn undo it?"
    ),
    IMPORT_CASES[1]: (
        "(principal point) By how much does each reduced coordinate change, and does that "
        "depend on the point?"
    ),
    IMPORT_CASES[2]: (
        "(pixel size) Which quantities does the pixel size convert — only the measured "
        "coordinates? And what does x = −c·u/w see of a factor on both?"
    ),
}


def check_import_mistakes(fn: Callable) -> None:
    """Check ``fn() -> dict``: for each of :data:`IMPORT_CASES` the pattern (one of
    :data:`PATTERNS`) that the misclosures of a wrongly imported image show.

    Oracle: a vertical image with known orientation imported with each mistake here, its
    misclosures at the true start values and a 4-parameter pattern fit (least squares; "no
    pattern" when the fit leaves more than 10 % of them).
    """
    got = call(fn, what="import_mistakes")
    if not isinstance(got, dict):
        raise CheckFailed(f"import_mistakes: expected a dict, got {type(got).__name__}")
    missing = [c for c in IMPORT_CASES if c not in got]
    if missing:
        raise CheckFailed(f"import_mistakes: no answer for {missing} (copy the keys exactly)")
    for case in IMPORT_CASES:
        if got[case] not in PATTERNS:
            raise CheckFailed(
                f"import_mistakes[{case!r}] = {got[case]!r}: choose one of {', '.join(PATTERNS)}"
            )
    truth = _import_patterns()
    wrong = [c for c in IMPORT_CASES if got[c] != truth[c][0]]
    if wrong:
        raise CheckFailed(
            f"import_mistakes: {len(wrong)} of 3 mispredicted — {', '.join(map(repr, wrong))}. "
            + " ".join(_HINT[c] for c in wrong),
            error=np.inf,
            tolerance=0.0,
        )
    success("; ".join(f"{c}: {truth[c][0]}" for c in IMPORT_CASES))


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
