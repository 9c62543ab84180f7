"""``orientviz reproduce geier``: Geier (1973) Fig. 8 beside orientviz's numbers.

For every task and every one of the ten surfaces the paper's printed true error (or m0,
or correlation) is set beside orientviz's value; the flag says whether orientviz's value
rounded to the paper's printed digits equals it (:mod:`orientviz.reproduce.rows`).

Labels (docs/geier_conventions.md says how each choice was made and how sensitive the
counts are to it, :mod:`orientviz.reproduce.geier_sensitivity`):

* calibration (image 2): **fitted** — the rotation order, the surfaces' heights, the
  stopping rule, the use of the printed gon values and the sign of the true error were
  chosen by matching these very numbers;
* exterior orientation, six jointly (image 2): **fitted** — the threshold of the
  reconstructed stopping rule was bracketed with these numbers (and the surfaces and
  rotation order chosen with the calibration of the same columns);
* the other tasks (trilateration, rotations, all ten parameters, both relative
  orientations): **predicted** — nothing was chosen by matching them.

The note of a row gives, where the Monte Carlo is run (``draws > 0``), the standard
deviation of orientviz's value over random shifts of the rounding grid.
"""

from __future__ import annotations

import copy

import numpy as np

from ..radar import fig8
from ..radar.data import load_fig8_paper
from ..radar.geier1973 import SURFACES
from .rows import Row


def _english(column: str) -> str:
    """The surface of a Fig. 8 column in English (the paper's headings are German)."""
    _, kind, radius, convex = SURFACES[column]
    if kind == "fig7":
        return "arbitrary heights of Fig. 7"
    if kind == "plane":
        return "plane"
    shape = "sphere" if kind == "sphere" else f"cylinder, axis {kind[-1]}"
    return f"{shape}, radius {radius / 1000:.0f} km, {'convex' if convex else 'concave'}"


#: Decimals the paper prints, by unit.
DECIMALS = {"m": 2, "1e-6": 0, "cc": 0, "1": 3}

TASK_LABELS = {
    "calibration": "1 calibration (image 2)",
    "trilateration": "2a trilateration (image 2)",
    "rotations": "2b rotation parameters (image 2)",
    "exterior": "2c exterior orientation, 6 jointly (image 2)",
    "relative_near_normal": "4a relative orientation, images 1-2",
    "all_ten": "3 all ten parameters (image 3)",
    "relative_general": "4a relative orientation, images 1-3",
}

#: Choices fitted on each task's numbers (tasks not listed: predicted).
FITTED: dict[str, tuple[str, ...]] = {
    "calibration": (
        "rotation order",
        "surface depth",
        "stopping rule",
        "printed-gon angles",
        "sign of the true error",
    ),
    "exterior": ("stopping rule",),
}
#: Counting group of each task.
GROUP = {"calibration": "calibration", "exterior": "exterior"}
OTHER = "other tasks"

#: Why a task reproduces only in part (shown in the task's summary row).
WHY = {
    "calibration": "with the fitted conventions and the reconstructed stopping rule "
    "(orientviz.radar.stopping)",
    "exterior": "reconstructed stopping rule; column 10's m0 is 0.3254 (see "
    "docs/geier_conventions.md)",
    "trilateration": (
        "the paper does not give its observation model for the separate station; orientviz "
        "adjusts the radial image distances"
    ),
    "rotations": (
        "uses orientviz's trilaterated station (the paper's differs) and the tangential "
        "components; the paper's model is not given"
    ),
    "relative_near_normal": (
        "orientviz adjusts all four image coordinates per pair (rigorous); the paper's weighting "
        "of the condition equations is not given; r ≈ 1 makes these errors rounding luck"
    ),
    "all_ten": (
        "image 3's rotations (6-18 gon) make the rounded data depend on third-order details of "
        "the rotation that the paper does not state; X0/x0, Y0/y0 correlate strongly"
    ),
    "relative_general": "as for images 1-2; orientviz finds no singularity (see the lesson)",
}


def paper_values() -> dict[str, object]:
    """Fig. 8 as printed, by row key ``"task|column|quantity"`` (a fresh copy).

    Numbers are floats/ints in the paper's units (digits by unit: :data:`DECIMALS`);
    the two blank columns of the general relative orientation are ``"no solution
    (…)"`` under the key ``"relative_general|column|solution"``.
    """
    paper = load_fig8_paper()
    out: dict[str, object] = {}
    for task, qs in paper["tasks"].items():
        for j, col in enumerate(paper["columns"]):
            status = paper.get("status", {}).get(task, {}).get(col)
            if status:
                german, _, english = status.partition(" (")  # the paper's words, then English
                out[f"{task}|{col}|solution"] = f'no solution ("{german}": {english.rstrip(")")})'
                continue
            for q, values in qs.items():
                if values[j] is not None:
                    out[f"{task}|{col}|{q}"] = values[j]
    return copy.deepcopy(out)


def _fmt(v: float, unit: str) -> float:
    d = DECIMALS[unit]
    r = round(float(v), d)
    return 0.0 if r == 0 else r


def _label(task: str) -> tuple[str, tuple[str, ...], str]:
    if task in FITTED:
        return "fitted", FITTED[task], GROUP[task]
    return "predicted", (), OTHER


def table(
    draws: int = 10, seed: int = 1973, stopping: str = "geier", *, paper: dict | None = None
) -> list[Row]:
    """Rows comparing Fig. 8 with orientviz.

    Parameters
    ----------
    draws : int
        Monte Carlo draws over the rounding per surface for the spread (0: none).
    seed : int
        Seed of the random generator of the Monte Carlo.
    stopping : {"geier", "converge"}
        Stopping rule of the single-image tasks ("geier": the rule reconstructed from
        Fig. 8, :mod:`orientviz.radar.stopping`).
    paper : dict, optional
        The paper's values by row key (default :func:`paper_values`).

    Returns
    -------
    list of Row
        One row per printed number (one per blank column), then one summary row per task.
    """
    results = fig8.run_all(stopping=stopping)
    cols = load_fig8_paper()["columns"]
    rng = np.random.default_rng(seed)
    spread = (
        {s: fig8.rounding_spread(s, rng=rng, draws=draws, tasks=tuple(fig8.TASKS)) for s in cols}
        if draws > 0
        else {}
    )
    return rows_from_results(results, paper, spread)


def rows_from_results(
    results: dict, paper: dict | None = None, spread: dict | None = None
) -> list[Row]:
    """The rows of :func:`table` for given task outcomes (e.g. under other conventions).

    Parameters
    ----------
    results : dict
        column → task → :class:`~orientviz.radar.fig8.TaskOutcome`
        (:func:`orientviz.radar.fig8.run_all`).
    paper : dict, optional
        The paper's values by row key (default :func:`paper_values`).
    spread : dict, optional
        column → task → quantity → (mean, σ) over rounding draws, shown in the notes.
    """
    pv_all = paper_values() if paper is None else paper
    spread = spread or {}
    fig = load_fig8_paper()
    cols = fig["columns"]
    heads = [f"{i + 1} {h} ({_english(c)})" for i, (h, c) in enumerate(zip(fig["headings"], cols))]
    rows: list[Row] = []
    for task, qs in fig["tasks"].items():
        label, fitted, group = _label(task)
        first = len(rows)
        for j, col in enumerate(cols):
            out = results[col][task]
            key = f"{task}|{col}|solution"
            if key in pv_all:
                failed = out.status != "ok" and "not determinable" in out.status
                rows.append(
                    Row(TASK_LABELS[task], heads[j], "solution", pv_all[key],
                        "none" if failed else "solved", f"orientviz: {out.status}",
                        label=label, fitted=fitted, group=group, key=key,
                        value=None if failed else 1.0)
                )  # fmt: skip
                continue
            for q in qs:
                key = f"{task}|{col}|{q}"
                if key not in pv_all:
                    continue
                unit = fig["units"][q]
                ov = out.values.get(q)
                note = "" if out.status == "ok" else out.status
                sd = spread.get(col, {}).get(task, {}).get(q)
                if sd is not None:
                    note += (
                        "; " if note else ""
                    ) + f"rounding spread σ = {sd[1]:.{DECIMALS[unit] + 1}f}"
                rows.append(
                    Row(TASK_LABELS[task], heads[j], f"{q} [{unit}]", pv_all[key],
                        None if ov is None else _fmt(ov, unit), note, label=label,
                        value=None if ov is None else float(ov), decimals=DECIMALS[unit],
                        fitted=fitted, group=group, key=key)
                )  # fmt: skip
        mine = [r for r in rows[first:] if r.match is not None]
        k = sum(bool(r.match) for r in mine)
        rows.append(
            Row(TASK_LABELS[task], "all columns", "numbers matching the printed digits", None,
                None, f"{k}/{len(mine)} {label}" + (f" ({', '.join(fitted)})" if fitted else "")
                + "; " + WHY[task])
        )  # fmt: skip
    return rows
