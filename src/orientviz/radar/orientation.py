"""Orientation tasks of a single radar panorama image (Geier 1973, tasks 1-3).

Every task adjusts image observations with :func:`orientviz.adjust.gauss_newton` and
returns a :class:`RadarResult`: the engine's fields (estimates, σ̂0 — the paper's m0,
the mean error of an image coordinate —, covariance, correlations, history) and the
estimated image ``result.image`` (a :class:`~orientviz.radar.ppi.RadarImage`).

* :func:`calibrate` — task 1 (Fig. 5): interior orientation x0, y0, h, m and the
  reference direction α0 (= κ) with station and axis known.
* :func:`station_by_trilateration` — task 2a: X0, Y0, Z0 from the radial image
  distances alone (closed form for three points, least squares for more).
* :func:`rotations` — task 2b: φ, ω, κ with the station known, from the tangential
  image components (the radial ones do not depend on the rotation).
* :func:`exterior` — task 2c: all six exterior parameters jointly.
* :func:`resect_all` — task 3: all ten parameters jointly.

Units: metres for coordinates, h and image coordinates; angles in radians; rotation
``R = R_φ R_ω R_κ`` unless the image says otherwise (see :mod:`orientviz.radar.ppi`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..adjust import Adjustment, gauss_newton
from ..errors import InputError, NotDeterminableError
from .ppi import (
    PARAMS,
    RadarImage,
    check_image_points,
    check_points,
    project_with_jacobian,
    tolerant,
)
from .stopping import GeierRun, geier_iterate
from .trilateration import sphere_ranges, trilaterate_three

F64 = NDArray[np.float64]
OBSERVES = ("xy", "radial", "tangential")


@dataclass
class RadarResult(Adjustment):
    """The result of a radar image's orientation task.

    Attributes
    ----------
    image : RadarImage
        The estimated image (the free parameters at their estimates, the others known).
    task : str
        The task's name (``"calibration"``, ``"trilateration"``, …).
    observe : {"xy", "radial", "tangential"}
        Which image observations entered.
    m0_linearized : float
        With ``stopping="geier"``: the linearised m0 of the last system solved (the
        value Geier prints), image m; NaN otherwise.
    stop_rule : str
        With ``stopping="geier"``: the branch of the reconstructed rule that ended the
        iteration; empty otherwise.
    """

    image: RadarImage | None = None
    task: str = ""
    observe: str = "xy"
    m0_linearized: float = float("nan")
    stop_rule: str = ""


@dataclass
class TrilaterationResult(RadarResult):
    """Task 2a's result: the station with the closed form's two candidates.

    Attributes
    ----------
    candidates : ndarray, shape (2, 3)
        The two stations of the closed form through three points (lower, upper Z), m.
    discriminant : float
        Its discriminant (≈ 0: the station near the plane of the three points), m².
    triangle : list of int
        The three points used for the closed form.
    """

    candidates: F64 | None = None
    discriminant: float = float("nan")
    triangle: list[int] = field(default_factory=list)


def _indices(free: Sequence[str]) -> list[int]:
    bad = [f for f in free if f not in PARAMS]
    if bad:
        raise InputError(f"unknown radar parameters {bad}; expected names out of {PARAMS}")
    return [PARAMS.index(f) for f in free]


def _check(points: ArrayLike, xy: ArrayLike) -> tuple[F64, F64]:
    P = check_points(points, "object points")
    L = check_image_points(xy, "image coordinates")
    if P.shape[0] != L.shape[0]:
        raise InputError(
            f"expected one image point per object point, got {L.shape[0]} and {P.shape[0]}"
        )
    return P, L


def image_equations(
    points: F64, xy_obs: F64, image: RadarImage, free: Sequence[str], observe: str = "xy"
) -> tuple[Callable[[F64], tuple[F64, F64]], F64, F64]:
    """The functional model of one image for :func:`~orientviz.adjust.gauss_newton`.

    Parameters
    ----------
    points : ndarray, shape (n, 3)
        Known object points, m.
    xy_obs : ndarray, shape (n, 2)
        Observed image coordinates, m.
    image : RadarImage
        Values of all ten parameters (the fixed ones stay at these values).
    free : sequence of str
        Names of the unknowns (out of :data:`~orientviz.radar.ppi.PARAMS`).
    observe : {"xy", "radial", "tangential"}
        ``"xy"``: both image coordinates (2n observations). ``"radial"``: the distance
        ‖bvec‖ from the principal point (n). ``"tangential"``: the component across the
        observed radius (n, observed value 0); it does not depend on the range.

    Returns
    -------
    equations : callable
        ``equations(u) -> (f, J)`` for the reduced vector u of the free parameters.
    u0 : ndarray
        Start values of the free parameters.
    l : ndarray
        Observations.
    """
    if observe not in OBSERVES:
        raise InputError(f"expected observe out of {OBSERVES}, got {observe!r}")
    idx = _indices(free)
    full0 = image.vector()
    seq = image.sequence
    centre0 = np.array([image.x0, image.y0])
    bobs = xy_obs - centre0
    robs = np.linalg.norm(bobs, axis=1)
    tdir = np.column_stack([-bobs[:, 1], bobs[:, 0]]) / np.where(robs > 0, robs, 1.0)[:, None]

    def full(u: F64) -> F64:
        p = full0.copy()
        p[idx] = u
        return p

    def equations(u: F64) -> tuple[F64, F64]:
        p = full(u)
        xy, J, _ = project_with_jacobian(points, RadarImage.from_vector(p, seq))
        J = J[:, :, idx]
        if observe == "xy":
            return xy.reshape(-1), J.reshape(-1, len(idx))
        b = xy - p[:2]
        if observe == "radial":
            r = np.linalg.norm(b, axis=1)
            e = b / r[:, None]
            Jr = np.einsum("ni,niu->nu", e, J)
            # r depends on x0, y0 through b = xy - (x0, y0): ∂r/∂x0 = e·(∂xy/∂x0 − (1, 0))
            for k, name in enumerate(free):
                if name in ("x0", "y0"):
                    Jr[:, k] -= e[:, 0 if name == "x0" else 1]
            return r, Jr
        ft = np.einsum("ni,ni->n", tdir, xy - xy_obs)
        return ft, np.einsum("ni,niu->nu", tdir, J)

    if observe == "xy":
        l = xy_obs.reshape(-1)
    elif observe == "radial":
        l = robs
    else:
        l = np.zeros(len(xy_obs))
    return tolerant(equations, l.size, len(idx)), full0[idx], l


def adjust_image(
    points: ArrayLike,
    xy: ArrayLike,
    approx: RadarImage,
    free: Sequence[str],
    *,
    observe: str = "xy",
    sigma: float | ArrayLike = 1.0,
    task: str = "radar image",
    labels: Sequence[str] | None = None,
    stopping: str = "converge",
    **engine,
) -> RadarResult:
    """Adjust any subset of the ten parameters of one image (the others held fixed).

    Parameters
    ----------
    points : array_like, shape (n, 3)
        Control points in object metres.
    xy : array_like, shape (n, 2)
        Their observed image coordinates in image metres.
    approx : RadarImage
        Approximate values of the free parameters, known values of the others.
    free : sequence of str
        Unknowns, e.g. ``("x0", "y0", "h", "m", "kappa")``.
    observe : {"xy", "radial", "tangential"}
        Which image observations enter (see :func:`image_equations`).
    sigma : float or array_like
        A-priori σ of an observation in image metres (weights 1/σ²): one value, one per
        point (both coordinates) or one per observation.
    task : str
        Name used in messages and in ``result.task``.
    labels : sequence of str, optional
        Point labels for the observation labels.
    stopping : {"converge", "geier"}
        Iterate to convergence (the engine's rule; default) or stop by the rule
        reconstructed by matching Geier's Fig. 8 (:mod:`orientviz.radar.stopping`).
    **engine
        Passed on to :func:`~orientviz.adjust.gauss_newton` (``tol``, ``xtol``, ``stop``,
        ``max_iter``, ``damping``).

    Returns
    -------
    RadarResult
        With ``image`` (the estimated :class:`RadarImage`), ``task`` and ``observe``
        (and ``m0_linearized``, ``stop_rule`` with ``stopping="geier"``).

    Raises
    ------
    NotDeterminableError
        Fewer observations than unknowns, or a singular normal matrix (names the
        parameters).
    """
    P, L = _check(points, xy)
    free = list(free)
    equations, u0, l = image_equations(P, L, approx, free, observe)
    if l.size < len(free):
        raise NotDeterminableError(
            f"{task}: {l.size} observations for {len(free)} unknowns ({', '.join(free)}); "
            f"need at least {len(free)}",
            free,
            len(free) - l.size,
        )
    sig = np.asarray(sigma, dtype=float)
    if observe == "xy" and sig.ndim == 1 and sig.shape[0] == len(P):
        sig = np.repeat(sig, 2)  # one σ per point for both coordinates
    sigma = sig
    labels = list(labels) if labels is not None else [str(i + 1) for i in range(len(P))]
    obs_labels = (
        [f"{p}/{c}" for p in labels for c in ("x", "y")]
        if observe == "xy"
        else [f"{p}/{observe[0]}" for p in labels]
    )
    if stopping == "geier":
        res = geier_iterate(
            equations, u0, l, sigma, names=free, obs_labels=obs_labels, context=task, **engine
        )
    elif stopping == "converge":
        engine.setdefault("tol", 1e-8)
        res = gauss_newton(
            equations, u0, l, sigma, names=free, obs_labels=obs_labels, context=task, **engine
        )
    else:
        raise InputError(f"expected stopping 'converge' or 'geier', got {stopping!r}")
    p = approx.vector()
    p[_indices(free)] = res.x
    geier = (
        {"m0_linearized": res.m0_linearized, "stop_rule": res.rule}
        if isinstance(res, GeierRun)
        else {}
    )
    return res.extend(
        RadarResult, image=RadarImage.from_vector(p, approx.sequence), task=task,
        observe=observe, **geier,
    )  # fmt: skip


def calibrate(points: ArrayLike, xy: ArrayLike, approx: RadarImage, **kw) -> RadarResult:
    """Task 1 (Fig. 5): interior orientation x0, y0, h, m and α0 (κ), station and axis known.

    ``approx`` carries the known station and tilts (φ, ω) and approximate x0, y0, h, m, κ.
    Equivalent to Geier's Fig. 5: the points are turned into the axis system with the
    known station and tilts, leaving only the "Verkantung" α0 = κ. See :func:`adjust_image`.
    """
    return adjust_image(
        points, xy, approx, ("x0", "y0", "h", "m", "kappa"), task="calibration", **kw
    )


def station_by_trilateration(
    points: ArrayLike, xy: ArrayLike, approx: RadarImage, *, upper: bool = True, **kw
) -> TrilaterationResult:
    """Task 2a: the station X0 from the ranges alone ("räumlicher Bogenschnitt").

    With three points the closed form (:func:`~orientviz.radar.trilateration.trilaterate_three`)
    gives both candidates; with more, the three points spanning the largest triangle give
    them and a least-squares adjustment of the radial distances starts from the chosen
    candidate (``upper=True``: the one with the larger Z, above the terrain — the airborne
    case, where the paper notes the ambiguity does not matter).

    Parameters
    ----------
    points, xy : array_like
        Object points (n, 3) and image coordinates (n, 2) in m, n ≥ 3.
    approx : RadarImage
        Known interior orientation (x0, y0, h, m); its X0 is not used.
    upper : bool
        Adopt the candidate with the larger Z (default) or the smaller one.

    Returns
    -------
    TrilaterationResult
        Unknowns X0, Y0, Z0 (observations: radial image distances, image m); with
        ``candidates`` (2, 3) — the candidates of the closed form —, ``discriminant`` and
        ``triangle``. For n = 3 the result is the closed form (redundancy 0).
    """
    P, L = _check(points, xy)
    n = len(P)
    if n < 3:
        raise NotDeterminableError(
            f"trilateration: {n} ranges for 3 unknowns (X0, Y0, Z0); need at least 3",
            ["X0", "Y0", "Z0"],
            3 - n,
        )
    s = sphere_ranges(L, approx)
    tri = _largest_triangle(P)
    lo, hi, disc = trilaterate_three(P[tri], s[tri])
    start = hi if upper else lo
    res = adjust_image(
        P,
        L,
        approx.with_(X0=tuple(start)),
        ("X0", "Y0", "Z0"),
        observe="radial",
        task="trilateration",
        **kw,
    )
    return res.extend(
        TrilaterationResult, candidates=np.vstack([lo, hi]), discriminant=float(disc), triangle=tri
    )


def _largest_triangle(P: F64) -> list[int]:
    """Indices of three points spanning a large triangle (greedy; exact for n = 3)."""
    if len(P) == 3:
        return [0, 1, 2]
    c = P.mean(axis=0)
    i = int(np.argmax(np.linalg.norm(P - c, axis=1)))
    j = int(np.argmax(np.linalg.norm(P - P[i], axis=1)))
    area = np.linalg.norm(np.cross(P[j] - P[i], P - P[i]), axis=1)
    k = int(np.argmax(area))
    return [i, j, k]


def rotations(points: ArrayLike, xy: ArrayLike, approx: RadarImage, **kw) -> RadarResult:
    """Task 2b: the rotation φ, ω, κ with station and interior orientation known.

    Uses the tangential image components only (the radial ones carry no information on
    the rotation); σ̂0 is therefore the mean error of the tangential component.
    """
    return adjust_image(
        points,
        xy,
        approx,
        ("phi", "omega", "kappa"),
        observe="tangential",
        task="rotation parameters",
        **kw,
    )


def exterior(points: ArrayLike, xy: ArrayLike, approx: RadarImage, **kw) -> RadarResult:
    """Task 2c: the six exterior parameters X0, Y0, Z0, φ, ω, κ jointly (interior known)."""
    return adjust_image(
        points,
        xy,
        approx,
        ("X0", "Y0", "Z0", "phi", "omega", "kappa"),
        task="exterior orientation",
        **kw,
    )


def resect_all(points: ArrayLike, xy: ArrayLike, approx: RadarImage, **kw) -> RadarResult:
    """Task 3: all ten parameters of the image jointly (interior and exterior)."""
    return adjust_image(points, xy, approx, PARAMS, task="all ten parameters", **kw)
