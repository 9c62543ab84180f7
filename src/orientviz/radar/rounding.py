"""How much of Geier's Fig. 8 is the luck of one rounding: the package's values over many draws.

Fig. 8 prints the true errors of every task after the image coordinates were rounded to
whole metres once. Shifting the whole-metre grid by a random sub-metre offset gives
another, equally likely set of rounding errors. :func:`rounding_draws` repeats the test
of :mod:`orientviz.radar.fig8` for many such shifts, so each printed number can be set
against the *distribution* of the package's values (:func:`paper_position`: where the
paper's value lies in it, in standard deviations), and
:func:`orientviz.plot.fig8.plot_rounding_distribution` draws it.

If the paper's program did what the package does, its values would be one more draw: a
position within about ±2σ, an rms position near 1 over many numbers. The calibration and
the joint exterior orientation behave so; the other tasks do not (the
reproductions chapter and docs/geier_conventions.md give the measured numbers).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..blas import blas_threads
from . import geier1973 as G
from .fig8 import TASKS, run_surface

F64 = NDArray[np.float64]

#: The tasks whose conventions were not chosen by matching the paper (the "other tasks").
OTHER_TASKS: tuple[str, ...] = (
    "trilateration",
    "rotations",
    "relative_near_normal",
    "all_ten",
    "relative_general",
)


@dataclass
class RoundingDraws:
    """The package's Fig. 8 values over random shifts of the rounding grid.

    Attributes
    ----------
    tasks : tuple of str
        Keys of :data:`~orientviz.radar.fig8.TASKS`.
    surfaces : tuple of str
        Columns of Fig. 8 (:data:`~orientviz.radar.geier1973.COLUMNS` order).
    draws : dict
        task → quantity → ndarray (n_draws, n_surfaces) in the paper's units; NaN where
        a draw gave no solution.
    own : dict
        task → quantity → ndarray (n_surfaces,): the values with the paper's own rounding
        (no shift), as ``orientviz reproduce geier`` shows them.
    """

    tasks: tuple[str, ...]
    surfaces: tuple[str, ...]
    draws: dict[str, dict[str, F64]] = field(default_factory=dict)
    own: dict[str, dict[str, F64]] = field(default_factory=dict)

    @property
    def n_draws(self) -> int:
        """Number of draws."""
        for d in self.draws.values():
            for a in d.values():
                return int(a.shape[0])
        return 0


def _collect(outcomes: dict, tasks, surfaces, j: int, store: dict, row: int | None) -> None:
    for t in tasks:
        o = outcomes[t]
        for q in TASKS[t]:
            v = o.values.get(q, np.nan)
            arr = store[t][q]
            if row is None:
                arr[j] = v
            else:
                arr[row, j] = v


def rounding_draws(
    *,
    rng: np.random.Generator,
    draws: int = 100,
    tasks: tuple[str, ...] = OTHER_TASKS,
    surfaces: tuple[str, ...] = G.COLUMNS,
    stopping: str = "geier",
) -> RoundingDraws:
    """Run the Fig. 8 tasks for ``draws`` random shifts of the whole-metre rounding grid.

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of the shifts (uniform in [−0.5, 0.5) m per image and axis, per draw;
        the same shift for all surfaces of one draw).
    draws : int
        Number of shifts (each solves all tasks and surfaces once more).
    tasks : tuple of str
        Keys of :data:`~orientviz.radar.fig8.TASKS` (default: the five other tasks).
    surfaces : tuple of str
        Columns of Fig. 8.
    stopping : {"geier", "converge"}
        Stopping rule of the single-image tasks (as in ``orientviz reproduce geier``).

    Returns
    -------
    RoundingDraws
    """
    tasks, surfaces = tuple(tasks), tuple(surfaces)
    n = len(surfaces)
    out = RoundingDraws(tasks, surfaces)
    out.draws = {t: {q: np.full((draws, n), np.nan) for q in TASKS[t]} for t in tasks}
    out.own = {t: {q: np.full(n, np.nan) for q in TASKS[t]} for t in tasks}
    with blas_threads(1):
        for j, s in enumerate(surfaces):
            _collect(run_surface(s, stopping=stopping, tasks=tasks, diagnose=False), tasks,
                     surfaces, j, out.own, None)  # fmt: skip
        for i in range(int(draws)):
            off = rng.uniform(-0.5, 0.5, (3, 2))
            for j, s in enumerate(surfaces):
                res = run_surface(s, offsets=off, stopping=stopping, tasks=tasks, diagnose=False)
                _collect(res, tasks, surfaces, j, out.draws, i)
    return out


def paper_position(dist: RoundingDraws, paper: dict) -> dict[str, dict[str, F64]]:
    """Where each printed value lies in the package's rounding distribution.

    Parameters
    ----------
    dist : RoundingDraws
    paper : dict
        The Fig. 8 table (:func:`orientviz.radar.data.load_fig8_paper`).

    Returns
    -------
    dict
        task → quantity → ndarray (n_surfaces,): (paper − mean of the draws) / standard
        deviation of the draws (NaN where the paper prints no number).
    """
    cols = list(paper["columns"])
    out: dict[str, dict[str, F64]] = {}
    for t in dist.tasks:
        out[t] = {}
        for q, a in dist.draws[t].items():
            pv = paper["tasks"][t][q]
            p = np.array([np.nan if pv[cols.index(s)] is None else pv[cols.index(s)]
                          for s in dist.surfaces], float)  # fmt: skip
            with np.errstate(invalid="ignore", divide="ignore"):
                out[t][q] = (p - np.nanmean(a, axis=0)) / np.nanstd(a, axis=0, ddof=1)
    return out


def _positions(pos: dict[str, dict[str, F64]], task: str | None) -> F64:
    tasks = [task] if task is not None else list(pos)
    z = np.concatenate(
        [np.ravel(v) for t in tasks for q, v in pos[t].items() if not q.startswith("r_")]
    )
    return z[np.isfinite(z)]


def rms_position(pos: dict[str, dict[str, F64]], task: str | None = None) -> float:
    """RMS of the positions (in σ) over the printed numbers of one task (or all tasks).

    The correlations r_x/z, r_x/φ, r_z/φ are left out (their spread over draws is tiny
    and says nothing about the rounding). One more draw would give about 1.
    """
    z = _positions(pos, task)
    return float(np.sqrt(np.mean(z**2))) if z.size else float("nan")


def share_outside(pos: dict[str, dict[str, F64]], task: str | None = None, k: float = 2.0) -> float:
    """Share of the printed numbers farther than ``k`` σ from the draws' mean (one more
    draw: about 5 % for k = 2)."""
    z = _positions(pos, task)
    return float(np.mean(np.abs(z) > k)) if z.size else float("nan")


__all__ = [
    "OTHER_TASKS",
    "RoundingDraws",
    "rounding_draws",
    "paper_position",
    "rms_position",
    "share_outside",
]
