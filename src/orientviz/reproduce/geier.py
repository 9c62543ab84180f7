"""``orientviz reproduce geier``: Geier (1973) Fig. 8 beside orientviz's numbers.

For every task and every one of the ten surfaces the paper's printed true error (or m0,
or correlation) is set beside orientviz's value rounded to the paper's digits. The note
says whether it matches to the printed digits, and otherwise how far it is off compared
with the spread that the rounding of the image coordinates alone causes (a Monte Carlo
over random sub-metre shifts of the rounding grid, seeded) and why.
"""

from __future__ import annotations

import numpy as np

from ..radar import fig8
from ..radar.data import load_fig8_paper
from . import Row

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

#: Why a task is expected to reproduce only in magnitude (shown where numbers differ).
WHY = {
    "calibration": "paper's stopping rule (orientviz.radar.stopping) reproduces all columns",
    "exterior": "paper's stopping rule; see docs/geier_conventions.md for column 10's m0",
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


def _short(status: str | None) -> str:
    if not status:
        return "—"
    return "singular matrix" if "singul" in status else "no usable solution"


def _fmt(v: float, unit: str) -> float:
    d = DECIMALS[unit]
    r = round(float(v), d)
    return 0.0 if r == 0 else r


def table(draws: int = 10, seed: int = 1973, stopping: str = "geier") -> list[Row]:
    """Rows comparing Fig. 8 with orientviz.

    Parameters
    ----------
    draws : int
        Monte Carlo draws over the rounding per surface for the spread (0: none).
    seed : int
        Seed of the random generator of the Monte Carlo.
    stopping : {"geier", "converge"}
        Stopping rule of the single-image tasks.

    Returns
    -------
    list of Row
        One row per printed number, then one summary row per task.
    """
    paper = load_fig8_paper()
    cols = paper["columns"]
    heads = [f"{i + 1} {h}" for i, h in enumerate(paper["headings"])]
    results = fig8.run_all(stopping=stopping)
    rng = np.random.default_rng(seed)
    spread = (
        {s: fig8.rounding_spread(s, rng=rng, draws=draws, tasks=tuple(fig8.TASKS)) for s in cols}
        if draws > 0
        else {}
    )
    rows: list[Row] = []
    summary: dict[str, list[int]] = {}
    for task, qs in paper["tasks"].items():
        hit = summary.setdefault(task, [0, 0])
        for j, col in enumerate(cols):
            out = results[col][task]
            status = paper.get("status", {}).get(task, {}).get(col)
            for q, values in qs.items():
                unit = paper["units"][q]
                label = f"{q} [{unit}]"
                pv = values[j]
                ov = out.values.get(q)
                if pv is None:
                    rows.append(
                        Row(
                            TASK_LABELS[task],
                            heads[j],
                            label,
                            _short(status),
                            None if ov is None else _fmt(ov, unit),
                            f"orientviz: {out.status}"
                            + (f"; {out.diagnosis}" if q == "m0" and out.diagnosis else ""),
                        )
                    )
                    continue
                if ov is None:
                    rows.append(Row(TASK_LABELS[task], heads[j], label, pv, None, out.status))
                    continue
                mine = _fmt(ov, unit)
                hit[1] += 1
                if abs(mine - pv) < 0.5 * 10.0 ** -DECIMALS[unit] + 1e-12:
                    hit[0] += 1
                    note = "matches the printed digits"
                else:
                    note = f"differs by {mine - pv:+.{DECIMALS[unit]}f}"
                sd = spread.get(col, {}).get(task, {}).get(q)
                if sd is not None:
                    note += f"; rounding spread σ = {sd[1]:.{DECIMALS[unit] + 1}f}"
                rows.append(Row(TASK_LABELS[task], heads[j], label, pv, mine, note))
    for task, (k, n) in summary.items():
        rows.append(
            Row(
                TASK_LABELS[task],
                "all columns",
                "numbers matching the printed digits",
                n,
                k,
                "" if k == n else WHY[task],
            )
        )
    return rows
