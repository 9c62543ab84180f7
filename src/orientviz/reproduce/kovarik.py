"""Kovarik (1968): passes of numerical relative orientation in an analog plotter.

``orientviz reproduce kovarik`` runs the simulated plotter
(:mod:`orientviz.orientation.plotter`) as Kovarik ran his desk computer: minimal
pre-orientation (first corrections of 100-150 c), by and z read at the nine points,
corrections computed and applied, repeated until a pass yields rotations below 1 c and
base corrections below 0.05 mm ("converged": what single by readings, σ = 5 µm in the
machine, can no longer resolve; Kovarik's last pass gave "several tenths" of c).

Experiments:

* relief: relative height differences of 6, 10 and 15 % (paper: 2-3, 4 and 5-6 passes,
  corrections shrinking about tenfold per pass), for the exact linearisation, Kovarik's
  9-point formula, the flat-terrain formula and the round-constant pre-orientation;
* wrong ordinate: the 9-point constants computed for 152.7 mm instead of 100 mm (paper:
  about three times as many passes). "Ordinate" read two ways: as the edge rows' image
  ordinate (k = 152.7/152.7 instead of 100/152.7) and as the projection distance (k
  too small by the same factor);
* sensitivity: relief counted as ± (twice the range), alone and together with a
  stricter end point (0.3 c, 1 µm readings) — the modelling choices that bring the
  relief law towards the paper's counts;
* instrument axes: corrections added to the dials vs converted through the φ-ω-κ axes.

Pass counts come out of the simulation (mean, min-max over ``n_trials`` random pairs);
nothing here is fitted to the paper.
"""

from __future__ import annotations

import numpy as np

from ..orientation.plotter import AnalogPlotter, config_with, true_pair
from ..orientation.preorient import preorientation_error
from . import Row

RELIEFS = ((0.06, "2-3"), (0.10, "4"), (0.15, "5-6"))


def run_experiment(
    formula: str,
    relief: float,
    *,
    n_trials: int = 12,
    seed: int = 1968,
    k: float | None = None,
    tol_c: float = 1.0,
    **config,
) -> dict:
    """Orient ``n_trials`` random pairs; return pass counts and per-pass corrections.

    Parameters
    ----------
    formula : str
        One of :data:`orientviz.orientation.plotter.FORMULAS`.
    relief : float
        Relative relief (range / projection distance).
    n_trials : int
        Number of random pairs (seeds ``seed``, ``seed + 1``, …).
    k : float, optional
        k used by the formula's constants (default: the configured ordinate / c).
    tol_c : float
        Convergence threshold for the rotation corrections, centesimal minutes.
    **config
        Changes to :class:`~orientviz.orientation.plotter.PlotterConfig`.

    Returns
    -------
    dict
        ``"passes"`` (n_trials,) (NaN where not converged in 30 passes),
        ``"corrections_c"`` list of per-pass largest rotation corrections (c),
        ``"converged"`` (n_trials,) bool.
    """
    passes, corr, conv = [], [], []
    for t in range(n_trials):
        rng = np.random.default_rng(seed + t)
        pair = true_pair(config_with(relief=relief, **config), rng=rng)
        run = AnalogPlotter(pair, "kovarik9", rng=rng).orient(formula, k=k, tol_c=tol_c)
        passes.append(run.n_passes if run.converged else np.nan)
        corr.append(run.corrections_c())
        conv.append(run.converged)
    return {"passes": np.array(passes, float), "corrections_c": corr, "converged": np.array(conv)}


def _fmt_passes(p: np.ndarray) -> str:
    ok = p[np.isfinite(p)]
    if ok.size == 0:
        return "no convergence in 30 passes"
    s = f"{ok.mean():.1f} ({ok.min():.0f}-{ok.max():.0f})"
    if ok.size < p.size:
        s += f", {p.size - ok.size} not converged"
    return s


def _fmt_corr(corr: list[np.ndarray], upto: int = 6) -> str:
    m = max(len(c) for c in corr)
    out = []
    for i in range(min(m, upto)):
        vals = [c[i] for c in corr if len(c) > i]
        out.append(f"{np.median(vals):.3g}")
    return " → ".join(out)


def table(n_trials: int = 12, seed: int = 1968) -> list[Row]:
    """Rows of the relief, wrong-ordinate and pre-orientation experiments."""
    rows: list[Row] = []
    for formula in ("kovarik9", "exact", "flat", "preorient"):
        for relief, paper in RELIEFS:
            r = run_experiment(formula, relief, n_trials=n_trials, seed=seed)
            case = f"relief {relief:.0%}, {formula}"
            rows.append(
                Row(
                    "relief",
                    case,
                    "passes",
                    paper if formula == "kovarik9" else None,
                    _fmt_passes(r["passes"]),
                    "mean (min-max) over random pairs",
                )
            )
            rows.append(
                Row(
                    "relief",
                    case,
                    "median largest rotation per pass [c]",
                    "100-150 → 10-30 → 1-9 → tenths" if formula == "kovarik9" else None,
                    _fmt_corr(r["corrections_c"]),
                )
            )
    for relief, paper in RELIEFS:
        r = run_experiment("kovarik9", 2 * relief, n_trials=n_trials, seed=seed)
        rows.append(
            Row(
                "relief (sensitivity)",
                f"relief ±{relief:.0%} (range {2 * relief:.0%}), kovarik9",
                "passes",
                paper,
                _fmt_passes(r["passes"]),
                "relief read as ± deviation instead of range",
            )
        )
    for relief, paper in RELIEFS:
        r = run_experiment(
            "kovarik9",
            2 * relief,
            n_trials=n_trials,
            seed=seed,
            tol_c=0.3,
            sigma_by=0.001,
            sigma_z=0.01,
        )
        rows.append(
            Row("relief (sensitivity)", f"relief ±{relief:.0%}, converged below 0.3 c, 1 µm readings",
                "passes", paper, _fmt_passes(r["passes"]),
                "a stricter end point plus ± relief: the combination closest to the paper")
        )  # fmt: skip
    for apply in ("counters", "axes"):
        r = run_experiment("kovarik9", 0.10, n_trials=n_trials, seed=seed, apply=apply)
        rows.append(
            Row("instrument axes", f"relief 10%, kovarik9, corrections applied to the {apply}"
                if apply == "counters" else "relief 10%, kovarik9, converted through the φ-ω-κ axes",
                "passes", None, _fmt_passes(r["passes"]),
                "Bernhard's axis corrections matter little for 100-150 c starts")
        )  # fmt: skip
    c = 152.7
    right = run_experiment("kovarik9", 0.10, n_trials=n_trials, seed=seed)
    wrong_a = run_experiment("kovarik9", 0.10, n_trials=n_trials, seed=seed, k=152.7 / c)
    wrong_b = run_experiment(
        "kovarik9", 0.10, n_trials=n_trials, seed=seed, k=(100 / c) * (100 / 152.7)
    )
    base = np.nanmean(right["passes"])
    for label, r, note in (
        ("ordinate = image ordinate of the edge rows (k = 1.0 instead of 0.655)", wrong_a, ""),
        ("ordinate = projection distance (k = 0.429 instead of 0.655)", wrong_b, ""),
    ):
        ratio = np.nanmean(r["passes"]) / base if np.isfinite(r["passes"]).any() else float("nan")
        rows.append(Row("wrong ordinate", label, "passes", None, _fmt_passes(r["passes"]), note))
        rows.append(
            Row(
                "wrong ordinate",
                label,
                "passes / passes with 100 mm",
                "about 3",
                f"{ratio:.2f}" if np.isfinite(ratio) else "diverges",
                f"correct: {_fmt_passes(right['passes'])}",
            )
        )
    pre = preorientation_error([25.0, 50.0, 100.0, 200.0], element="all", ordinate=110.0)
    for a, er, ee in zip(pre["alpha_c"], pre["round"], pre["exact"]):
        rows.append(
            Row(
                "pre-orientation",
                f"rotations of {a:.0f} c (ordinate 110 mm)",
                "error Δω, Δφ [c] round / exact linearisation",
                None,
                f"{er[0]:+.2f}, {er[1]:+.2f} / {ee[0]:+.2f}, {ee[1]:+.2f}",
                "round constants: K = 1.59 in Δω belongs to 117 mm, 20 and 0.005 to 110 mm",
            )
        )
    return rows
