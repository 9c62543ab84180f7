"""Checks of the answers a student reads off a lesson's slider ("move it until …").

A widget question asks the student to move a slider until something happens, to type the
value they found, and to explain it. The check does not trust the widget: it finds the
value where the event happens by its own search (bisection or a scan on fine steps of the
quantity the widget prints), accepts the answer within one slider step (plus 2 %), and
names the plausible misreadings (another event, another unit).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable

import numpy as np

from ..orientation.absolute import similarity_transform
from ..orientation.examples import similarity_example
from ..orientation.plotter import AnalogPlotter
from ..radar.scene import trilateration_scene
from ..simulate import model_field
from ..simulate import systematic as se
from ..units import RHO_C
from ._common import CheckFailed, NotWrittenError, call, success

__all__ = [
    "answer_value",
    "check_base_height",
    "check_model_radial",
    "check_similarity_scale",
    "check_tilt",
    "model_radial_z_cm",
    "normal_case_sigma_z",
    "similarity_scale_ppm",
    "tilt_shift_um",
    "check_event_at",
    "first_event",
    "check_slider_answer",
    "crossing",
    "check_pair_kappa",
    "pair_parallax_rms",
    "check_trilateration_delta",
    "trilateration_shift",
]


def crossing(
    f: Callable[[float], float], target: float, lo: float, hi: float, steps: int = 200
) -> float:
    """The smallest ``t`` in [lo, hi] with ``f(t) = target``, for ``f(lo) < target``.

    Scans ``steps`` steps for the first sign change of ``f − target``, then bisects it to
    1e-9 of the interval. Raises ValueError if ``f`` never reaches ``target``.
    """
    ts = np.linspace(lo, hi, steps + 1)
    vals = np.array([f(float(t)) for t in ts]) - target
    if vals[0] >= 0:
        raise ValueError(f"f({lo}) already ≥ {target}")
    above = np.flatnonzero(vals >= 0)
    if above.size == 0:
        raise ValueError(f"f stays below {target} on [{lo}, {hi}]")
    a, b = float(ts[above[0] - 1]), float(ts[above[0]])
    while b - a > 1e-9 * (hi - lo):
        m = 0.5 * (a + b)
        if f(m) - target < 0:
            a = m
        else:
            b = m
    return 0.5 * (a + b)


def answer_value(answer: object, what: str) -> float | None:
    """The number a student gave: a value, or a function of no arguments returning it
    (the lessons' form, so that a blank raises only in its check); None if not written."""
    if callable(answer):
        answer = call(answer, what=what)
    if answer is None or answer is Ellipsis:
        return None
    try:
        return float(answer)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise CheckFailed(f"{what}: expected a number, got {answer!r}") from None


def check_slider_answer(
    what: str,
    answer: object,
    expected: float,
    step: float,
    unit: str,
    wrong: Iterable[tuple[str, float]] = (),
) -> None:
    """Accept ``answer`` within one slider ``step`` (+ 2 %) of ``expected``; name misreadings.

    Parameters
    ----------
    what : str
        What was asked, for the messages.
    answer : float, callable or None
        The student's value, or a function returning it (None or ``...``: not written yet).
    expected : float
        The value the check found itself.
    step : float
        The slider's step (same unit).
    unit : str
        Unit of the values, for the messages.
    wrong : iterable of (str, float)
        Plausible wrong answers: what the mistake is, and the value it would give.
    """
    got = answer_value(answer, what)
    if got is None:
        raise NotWrittenError(f"{what}: not written yet (type the value you read off the slider)")
    if not math.isfinite(got):
        raise CheckFailed(f"{what}: {got} is not a number")
    tol = step + 0.02 * abs(expected)
    err = abs(got - expected)
    if err <= tol:
        success(f"{what}: {got:g} {unit} (the check finds {expected:.3g} {unit})")
        return
    for name, value in wrong:
        if abs(got - value) <= step + 0.02 * abs(value):
            raise CheckFailed(
                f"✗ {what}: {got:g} {unit} — that is {name}; the question asks for another value",
                err / max(abs(expected), 1e-300),
                tol / max(abs(expected), 1e-300),
            )
    side = "too large" if got > expected else "too small"
    raise CheckFailed(
        f"✗ {what}: {got:g} {unit} is {side} (more than one slider step, {step:g} {unit}, "
        f"away from where it happens); move the slider again and read the printed value",
        err / max(abs(expected), 1e-300),
        tol / max(abs(expected), 1e-300),
    )


# ---------------------------------------------------------------- lesson 05: the pair
def pair_parallax_rms(
    pair: object, settings: np.ndarray, kappa_offset_c: float
) -> tuple[float, float]:
    """RMS and largest absolute y-parallax (mm) at Kovarik's nine points, κ turned by an offset.

    Parameters
    ----------
    pair : TruePair
        The photographs (``orientviz.orientation.plotter.true_pair``).
    settings : ndarray, shape (5,)
        Dials by, bz (mm), ω, φ, κ (rad).
    kappa_offset_c : float
        Added to κ, centesimal minutes.
    """

    s = np.asarray(settings, dtype=float).copy()
    s[4] += kappa_offset_c / RHO_C
    plotter = AnalogPlotter(pair, settings=s)  # type: ignore[arg-type]
    X, Y, Z = plotter.scheme_points("kovarik9")
    p, _ = plotter.parallax_at(np.column_stack([X, Y, Z]))
    return float(np.sqrt(np.mean(p**2))), float(np.max(np.abs(p)))


def check_pair_kappa(
    answer_c: object, pair: object, settings: np.ndarray, target_mm: float, step_c: float
) -> None:
    """The κ offset (c) from ``settings`` at which the RMS y-parallax at the nine points
    reaches ``target_mm`` (lesson 05's live pair)."""

    def rms(t: float) -> float:
        return pair_parallax_rms(pair, settings, t)[0]

    def largest(t: float) -> float:
        return pair_parallax_rms(pair, settings, t)[1]

    expected = crossing(rms, target_mm, 0.0, 250.0)
    wrong = [
        (
            "where the LARGEST arrow reaches it, not the RMS",
            crossing(largest, target_mm, 0.0, 250.0),
        ),
        ("the offset in radians, not in c", expected / RHO_C),
        ("the offset in gon, not in c", expected / 100.0),
        ("the offset in degrees, not in c", expected * 0.009),
    ]
    what = f"κ offset for an RMS y-parallax of {target_mm * 1000:g} µm"
    value = answer_value(answer_c, what)
    check_slider_answer(what, None if value is None else abs(value), expected, step_c, "c", wrong)


# ---------------------------------------------------------------- lesson 14: three spheres
def trilateration_shift(centres: np.ndarray, ranges: np.ndarray, station: np.ndarray,
                        delta_m: float) -> float:  # fmt: skip
    """Distance (m) of the upper trilateration candidate from ``station`` when every one of
    the three ``ranges`` (m) about ``centres`` (3, 3) m is too long by ``delta_m``."""

    sc = trilateration_scene(centres, np.asarray(ranges, dtype=float) + delta_m)
    return float(np.linalg.norm(sc["candidates"][1] - np.asarray(station, dtype=float)))


def check_trilateration_delta(
    answer_m: object, centres: np.ndarray, ranges: np.ndarray, station: np.ndarray,
    target_m: float, step_m: float,
) -> None:  # fmt: skip
    """The common range error (m) that moves the upper candidate ``target_m`` from the
    station (lesson 14's live radar scene)."""

    def f(t: float) -> float:
        return trilateration_shift(centres, ranges, station, t)

    expected = crossing(f, target_m, 0.0, 200.0 * step_m)
    wrong = [("the shift itself, not the range error that causes it", target_m),
             ("the range error in km, not in m", expected / 1000.0)]  # fmt: skip
    what = f"range error that moves the station {target_m:g} m"
    value = answer_value(answer_m, what)
    check_slider_answer(what, None if value is None else abs(value), expected, step_m, "m", wrong)


# ---------------------------------------------------------------- the event at the answer
def first_event(happens: Callable[[float], bool], lo: float, hi: float, step: float) -> float:
    """The smallest slider position ``lo + k·step`` (k = 0, 1, …) at which ``happens`` is true.

    Assumes the event, once it happens, goes on happening further along the slider (the
    quantity behind it grows with the slider), and bisects over the slider's positions:
    about log2((hi − lo)/step) calls of ``happens``. Raises ValueError if it does not happen
    at ``hi``.

    Parameters
    ----------
    happens : callable
        ``happens(value) -> bool`` for a slider value (same unit as ``lo``, ``hi``, ``step``).
    lo, hi, step : float
        The slider's range and step.
    """
    n = int(round((hi - lo) / step))
    if not happens(lo + n * step):
        raise ValueError(f"it does not happen on the slider ({lo:g} … {hi:g})")
    if happens(lo):
        return float(lo)
    a, b = 0, n  # not at a, at b
    while b - a > 1:
        m = (a + b) // 2
        if happens(lo + m * step):
            b = m
        else:
            a = m
    return float(lo + b * step)


def check_event_at(
    what: str,
    answer: object,
    happens: Callable[[float], bool],
    step: float,
    unit: str,
    lo: float,
    hi: float,
    wrong: Iterable[tuple[str, float]] = (),
) -> None:
    """Accept ``answer`` if the event happens there and not one slider ``step`` before.

    For a slider whose every position costs an adjustment, the check does not search:
    it evaluates ``happens`` (the event, e.g. "the test finds the blunder") at the answer
    and one step below it — the definition of "the smallest value at which it happens".

    Parameters
    ----------
    what : str
        What was asked, for the messages.
    answer : float, callable or None
        The student's value, or a function returning it.
    happens : callable
        ``happens(value) -> bool``, computed by the library from the slider's value.
    step, unit : float, str
        The slider's step and unit.
    lo, hi : float
        The slider's range.
    wrong : iterable of (str, float)
        Plausible misreadings (what, value), named when the answer is one of them.
    """
    got = answer_value(answer, what)
    if got is None:
        raise NotWrittenError(f"{what}: not written yet (type the value you read off the slider)")
    if not (lo - 1e-9 <= got <= hi + 1e-9) or not math.isfinite(got):
        raise CheckFailed(f"✗ {what}: {got:g} {unit} is outside the slider ({lo:g} … {hi:g})")
    at, before = bool(happens(got)), bool(happens(got - step)) if got - step >= lo else False
    if at and not before:
        success(f"{what}: {got:g} {unit} (not yet at {got - step:g} {unit})")
        return
    for name, value in wrong:
        if abs(got - value) <= 0.5 * step:
            raise CheckFailed(f"✗ {what}: {got:g} {unit} — that is {name}")
    if not at:
        raise CheckFailed(
            f"✗ {what}: at {got:g} {unit} it does not happen yet — move the slider further"
        )
    raise CheckFailed(
        f"✗ {what}: it happens already at {got - step:g} {unit} — the question asks for the "
        "smallest value"
    )


# ---------------------------------------------------------------- lessons 02, 04, 07, 11
def tilt_shift_um(x_mm: float, c_mm: float, phi_c: float) -> float:
    """Absolute shift (µm) of the image of a ray at image abscissa ``x_mm`` when the camera is
    tilted by φ (centesimal minutes) about its y axis: the ray's angle to the axis,
    atan(x/c), changes by φ, so x' = c·tan(atan(x/c) − φ) (closed form)."""
    phi = phi_c / RHO_C
    return abs(c_mm * math.tan(math.atan2(x_mm, c_mm) - phi) - x_mm) * 1000.0


def check_tilt(answer: object, x_mm: float, c_mm: float, target_um: float, step_c: float) -> None:
    """The tilt φ (c) that moves the image at ``x_mm`` by ``target_um`` (lesson 02)."""
    expected = crossing(lambda t: tilt_shift_um(x_mm, c_mm, t), target_um, 0.0, 100.0)
    centre = crossing(lambda t: tilt_shift_um(0.0, c_mm, t), target_um, 0.0, 100.0)
    wrong = [
        ("the tilt that moves the image CENTRE so far, not the edge", centre),
        ("the tilt in cc, not in c", expected * 100.0),
        ("the tilt in gon, not in c", expected / 100.0),
    ]
    what = f"φ that moves the image at x = {x_mm:g} mm by {target_um:g} µm"
    value = answer_value(answer, what)
    check_slider_answer(what, None if value is None else abs(value), expected, step_c, "c", wrong)


def normal_case_sigma_z(base_height: float, height_m: float, c_mm: float, sigma_um: float) -> float:
    """σ_Z (m) of a point intersected in the normal case: √2 (H/B)(H/c) σ (closed form)."""
    return math.sqrt(2.0) / base_height * (height_m / (c_mm / 1000.0)) * sigma_um * 1e-6


def check_base_height(
    answer: object, height_m: float, c_mm: float, sigma_um: float, target_m: float, step: float
) -> None:
    """The B/H at which σ_Z of the normal case falls to ``target_m`` (lesson 04)."""

    def excess(bh: float) -> float:  # decreasing in B/H: find where it drops to the target
        return -normal_case_sigma_z(bh, height_m, c_mm, sigma_um)

    expected = crossing(excess, -target_m, 0.05, 3.0)
    sxy = height_m / (c_mm / 1000.0) * sigma_um * 1e-6
    wrong = [(f"where σ_Z equals σ_X ({sxy * 100:.1f} cm), not {target_m * 100:g} cm",
              crossing(excess, -sxy, 0.05, 3.0))]  # fmt: skip
    what = f"B/H for σ_Z = {target_m * 100:g} cm"
    check_slider_answer(what, answer, expected, step, "", wrong)


def similarity_scale_ppm(layout: str, sigma_cm: float, seed: int = 1) -> float:
    """A-priori σ of the scale (ppm) of the 7-parameter similarity of lesson 07's model
    with control in ``layout`` of σ ``sigma_cm`` (the library's similarity_transform)."""
    ex = similarity_example(layout, sigma_cm / 100.0, rng=np.random.default_rng(seed))
    res = similarity_transform(
        ex.source, ex.target, sigma_target=sigma_cm / 100.0, point_ids=ex.ids
    )
    i = list(res.names).index("scale")
    return float(res.std(a_posteriori=False)[i] * 1e6 / res.x[i])


def check_similarity_scale(
    answer: object, layout: str, target_ppm: float, step_cm: float, seed: int = 1
) -> None:
    """The control σ (cm) at which the scale's a-priori σ reaches ``target_ppm`` (lesson 07)."""
    expected = crossing(lambda s: similarity_scale_ppm(layout, s, seed), target_ppm, 0.01, 50.0)
    wrong = [("the σ in m, not in cm", expected / 100.0), ("the σ in mm, not in cm", expected * 10)]
    what = f"control σ for a scale σ of {target_ppm:g} ppm ({layout})"
    check_slider_answer(what, answer, expected, step_cm, "cm", wrong)


def model_radial_z_cm(strength_um: float) -> float:
    """RMS height deformation (cm) of lesson 11's stereo model (``model_field``, n = 5)
    oriented from images with radial distortion of ``strength_um`` µm (``se.radial``)."""
    return float(model_field(se.radial(strength_um), n=5).rms()[2] * 100.0)


def check_model_radial(answer: object, target_cm: float, step_um: float) -> None:
    """The radial distortion (µm) that bends lesson 11's model by ``target_cm`` RMS in Z."""
    # the deformation grows smoothly with the distortion: a coarse scan finds the crossing
    expected = crossing(model_radial_z_cm, target_cm, 0.0, 200.0, steps=20)
    xy = crossing(lambda s: float(np.hypot(*model_field(se.radial(s), n=5).rms()[:2]) * 100),
                  target_cm, 0.0, 2000.0, steps=20)  # fmt: skip
    wrong = [("where the PLANIMETRIC deformation reaches it, not the height", xy)]
    what = f"radial distortion for an RMS height deformation of {target_cm:g} cm"
    check_slider_answer(what, answer, expected, step_um, "µm", wrong)
