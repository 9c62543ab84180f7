"""Geier's test (Fig. 8): every task on every surface, with the conventions established in
docs/geier_conventions.md (some of them fitted on the printed numbers).

For each of the ten surfaces (:data:`~orientviz.radar.geier1973.COLUMNS`) the image
coordinates of the 25 points in images 1-3 are computed without error and rounded to
whole metres; then

* the near-normal image 2: calibration, trilateration (a), rotation parameters (b, with
  the trilaterated station), the joint six exterior parameters (c), and the relative
  orientation to the normal image 1 (interior orientations given);
* the general image 3: all ten parameters jointly, and its relative orientation to
  image 1.

Each number is a *true error* — estimate minus the true value of Fig. 7 — in the
paper's units (:data:`UNITS`): m, 10⁻⁶ for the scale, cc for angles; ``m0`` is σ̂0, the
mean error of one image coordinate in m. :func:`rounding_spread` repeats the test with
the rounding grid shifted by random sub-metre offsets, which measures how much of each
number is the luck of one particular rounding.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..blas import blas_threads
from ..errors import NotDeterminableError
from ..units import RHO_CC
from . import geier1973 as G
from .diagnostics import pair_geometry, weakest_direction
from .orientation import calibrate, exterior, resect_all, rotations, station_by_trilateration
from .pair import relative_orientation
from .ppi import PARAMS, RadarImage, project

F64 = NDArray[np.float64]

#: Tasks in the order of Fig. 8, with the quantities the paper prints for each.
TASKS: dict[str, tuple[str, ...]] = {
    "calibration": ("m0", "x0", "y0", "h", "m", "alpha0"),
    "trilateration": ("m0", "X02", "Y02", "Z02"),
    "rotations": ("m0", "phi", "omega", "kappa"),
    "exterior": ("m0", "X02", "Y02", "Z02", "phi", "omega", "kappa"),
    "relative_near_normal": (
        "m0", "X02", "Y02", "Z02", "phi", "omega", "kappa", "r_x/z", "r_x/phi", "r_z/phi",
    ),
    "all_ten": ("m0", "X03", "Y03", "Z03", "phi3", "omega3", "kappa3", "x0", "y0", "h", "m"),
    "relative_general": ("m0", "X03", "Y03", "Z03", "phi3", "omega3", "kappa3"),
}  # fmt: skip

#: Unit of each quantity as printed in Fig. 8.
UNITS: dict[str, str] = {
    "m0": "m", "x0": "m", "y0": "m", "h": "m", "m": "1e-6", "alpha0": "cc",
    "X02": "m", "Y02": "m", "Z02": "m", "X03": "m", "Y03": "m", "Z03": "m",
    "phi": "cc", "omega": "cc", "kappa": "cc", "phi3": "cc", "omega3": "cc", "kappa3": "cc",
    "r_x/z": "1", "r_x/phi": "1", "r_z/phi": "1",
}  # fmt: skip

#: Paper quantity → parameter name in :data:`~orientviz.radar.ppi.PARAMS`.
_PARAM_OF = {
    "x0": "x0", "y0": "y0", "h": "h", "m": "m", "alpha0": "kappa",
    "X02": "X0", "Y02": "Y0", "Z02": "Z0", "X03": "X0", "Y03": "Y0", "Z03": "Z0",
    "phi": "phi", "omega": "omega", "kappa": "kappa",
    "phi3": "phi", "omega3": "omega", "kappa3": "kappa",
}  # fmt: skip
_FACTOR = {"m": 1.0, "1e-6": 1e6, "cc": RHO_CC, "1": 1.0}


@dataclass
class TaskOutcome:
    """One task on one surface: the true errors in the paper's units, or why none."""

    task: str
    surface: str
    values: dict[str, float] = field(default_factory=dict)
    status: str = "ok"
    adjustment: Any = None
    diagnosis: str = ""


def rounded_coordinates(xy: ArrayLike, offset: ArrayLike | None = None) -> F64:
    """Round image coordinates to whole metres on a grid shifted by ``offset`` (m, (2,))."""
    xy = np.asarray(xy, float)
    if offset is None:
        return np.round(xy)
    off = np.asarray(offset, float)
    return np.round(xy + off) - off


def _errors(task: str, surface: str, res, truth: RadarImage, names) -> TaskOutcome:
    est = res.image.vector()
    tv = truth.vector()
    out = TaskOutcome(task, surface, adjustment=res)
    # the stopping rule of Fig. 8 reports the linearised m0 (the value the paper prints)
    out.values["m0"] = float(res.m0_linearized if res.stop_rule else res.sigma0)
    for q in names:
        if q in _PARAM_OF:
            k = PARAMS.index(_PARAM_OF[q])
            out.values[q] = float((est[k] - tv[k]) * _FACTOR[UNITS[q]])
    return out


def run_surface(
    surface: str,
    *,
    rounded: bool = True,
    offsets: ArrayLike | None = None,
    stopping: str = "geier",
    tasks: tuple[str, ...] | None = None,
    sequence: str = "pok",
    dz: float = 0.0,
    truth: dict[int, RadarImage] | None = None,
    rel: float | None = None,
    diagnose: bool = True,
) -> dict[str, TaskOutcome]:
    """Run the tasks of Fig. 8 on one surface.

    Parameters
    ----------
    surface : str
        A key of :data:`~orientviz.radar.geier1973.SURFACES`.
    rounded : bool
        Round the image coordinates to whole metres (the paper's Fig. 8) or keep them
        error-free (the paper's check of the iteration).
    offsets : array_like, shape (3, 2), optional
        Sub-metre shifts of the rounding grid per image (rows: images 1, 2, 3).
    stopping : {"geier", "converge"}
        Stopping rule of the single-image tasks (see :mod:`orientviz.radar.stopping`).
    tasks : tuple of str, optional
        A subset of :data:`TASKS`.
    sequence : {"pok", "opk"}
        Rotation sequence of the true images and of the adjustment (the conventions page:
        "pok" is the one chosen by matching the calibration; "opk" for the sensitivity).
    dz : float
        Shift of all 25 heights of the surface, m (sensitivity of the chosen heights).
    truth : dict of int to RadarImage, optional
        True images 1-3 instead of Fig. 7's (sensitivity of the angle inputs).
    rel : float, optional
        Threshold of the reconstructed stopping rule (default
        :data:`~orientviz.radar.stopping.GEIER_RELATIVE_M0`).
    diagnose : bool
        Describe each relative orientation's geometry in ``TaskOutcome.diagnosis``
        (condition number, weakest direction, the pair at the approximations); False
        leaves it empty (repeated runs that read only the values and the status).

    Returns
    -------
    dict of str to TaskOutcome
    """
    tasks = tuple(TASKS) if tasks is None else tasks
    T = G.images(sequence) if truth is None else truth
    A = G.approximations(sequence)
    P = G.points(surface) + np.array([0.0, 0.0, float(dz)])
    kw = {} if rel is None or stopping != "geier" else {"rel": float(rel)}
    off = np.zeros((3, 2)) if offsets is None else np.asarray(offsets, float).reshape(3, 2)
    xy = {}
    for i in (1, 2, 3):
        exact = project(P, T[i])
        xy[i] = rounded_coordinates(exact, off[i - 1]) if rounded else exact
    out: dict[str, TaskOutcome] = {}
    a2, a3 = A[2], A[3]
    ext2 = T[2].with_(X0=a2.X0, phi=a2.phi, omega=a2.omega, kappa=a2.kappa)
    for task in tasks:
        names = TASKS[task]
        try:
            if task == "calibration":
                start = T[2].with_(x0=a2.x0, y0=a2.y0, h=a2.h, m=a2.m, kappa=G.alpha0_approx())
                res = calibrate(P, xy[2], start, stopping=stopping, **kw)
            elif task == "trilateration":
                res = station_by_trilateration(P, xy[2], T[2].with_(X0=a2.X0))
            elif task == "rotations":
                X0 = out["trilateration"].adjustment.image.X0 if "trilateration" in out else T[2].X0
                res = rotations(P, xy[2], ext2.with_(X0=X0), stopping=stopping, **kw)
            elif task == "exterior":
                res = exterior(P, xy[2], ext2, stopping=stopping, **kw)
            elif task == "all_ten":
                res = resect_all(P, xy[3], a3, stopping=stopping, **kw)
            elif task in ("relative_near_normal", "relative_general"):
                img = 2 if task == "relative_near_normal" else 3
                start = (
                    ext2
                    if img == 2
                    else T[3].with_(X0=a3.X0, phi=a3.phi, omega=a3.omega, kappa=a3.kappa)
                )
                res = relative_orientation(xy[1], T[1], xy[img], start, damping="lm")
            else:
                raise KeyError(task)
        except NotDeterminableError as exc:
            out[task] = TaskOutcome(task, surface, status=f"not determinable: {exc}")
            continue
        truth = T[3] if task in ("all_ten", "relative_general") else T[2]
        o = _errors(task, surface, res, truth, names)
        if task.startswith("relative"):
            C = res.correlations()
            o.values.update(
                {"r_x/z": abs(C[0, 2]), "r_x/phi": abs(C[0, 3]), "r_z/phi": abs(C[2, 3])}
            )
        if task.startswith("relative") and diagnose:
            cond, weak = weakest_direction(res, block="image2")
            geo = pair_geometry(xy[1], T[1], xy[img], start, res.points)
            o.diagnosis = (
                f"condition number {cond:.3g}, weakest: "
                + ", ".join(f"{n} {s:.2f}" for n, s in weak[:3])
                + f"; at the approximations: {geo.summary()}"
            )
        if not res.converged:
            o.status = f"not converged: {res.reason}"
        out[task] = o
    return out


def run_all(**kw) -> dict[str, dict[str, TaskOutcome]]:
    """:func:`run_surface` for all ten columns of Fig. 8 (same keyword arguments)."""
    with blas_threads(1):  # hundreds of tiny adjustments
        return {s: run_surface(s, **kw) for s in G.COLUMNS}


def rounding_spread(
    surface: str,
    *,
    rng: np.random.Generator,
    draws: int = 50,
    tasks: tuple[str, ...] = ("calibration", "exterior"),
    stopping: str = "converge",
) -> dict[str, dict[str, tuple[float, float]]]:
    """Spread of the true errors over random shifts of the rounding grid.

    Each draw shifts the whole-metre grid of every image by offsets uniform in
    [−0.5, 0.5) m, so the rounding errors are a fresh, equally likely pattern.

    Returns
    -------
    dict
        task → quantity → (mean, standard deviation) over the draws, paper units.
    """
    acc: dict[str, dict[str, list[float]]] = {t: {} for t in tasks}
    with blas_threads(1):  # hundreds of tiny adjustments
        for _ in range(draws):
            off = rng.uniform(-0.5, 0.5, (3, 2))
            res = run_surface(surface, offsets=off, stopping=stopping, tasks=tasks, diagnose=False)
            for t, o in res.items():
                for q, v in o.values.items():
                    acc[t].setdefault(q, []).append(v)
    return {
        t: {q: (float(np.mean(v)), float(np.std(v, ddof=1))) for q, v in d.items()}
        for t, d in acc.items()
    }
