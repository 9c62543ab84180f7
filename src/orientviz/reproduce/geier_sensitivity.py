"""How much Geier's Fig. 8 counts depend on each choice that was fitted to them.

``orientviz reproduce geier`` matches the calibration 60/60 and the joint exterior
orientation 69/70 — with conventions chosen by matching those numbers
(docs/geier_conventions.md). :func:`sensitivity` changes one choice at a time and
recounts every group (calibration, exterior, other tasks), so the docs can say how
much each choice matters:

* rotation order: ω-φ-κ instead of φ-ω-κ;
* surface depth: all heights of a surface shifted by ±1, ±10, ±100 m;
* stopping rule: iterate to convergence; the reconstructed rule's threshold 0.03 %,
  0.3 %, 1 % instead of 0.1 %;
* printed-gon angles: the round radian values 0.0015, 0.0020, 0.0025 rad behind image
  2's printed angles;
* sign of the true error: truth minus estimate instead of estimate minus truth.

Run ``python -m orientviz.reproduce.geier_sensitivity`` for the table (about 15 runs of
the whole Fig. 8 test).
"""

from __future__ import annotations

from dataclasses import replace

from ..blas import blas_threads
from ..radar import fig8
from ..radar import geier1973 as G
from .geier import rows_from_results
from .rows import counts

#: name → keyword arguments of :func:`orientviz.radar.fig8.run_surface` (None: the default).
CHOICES: dict[str, dict | None] = {
    "as reproduced (φ-ω-κ, heights as chosen, reconstructed rule 0.1 %)": {},
    "rotation order ω-φ-κ": {"sequence": "opk"},
    "all heights +1 m": {"dz": 1.0},
    "all heights −1 m": {"dz": -1.0},
    "all heights +10 m": {"dz": 10.0},
    "all heights −10 m": {"dz": -10.0},
    "all heights +100 m": {"dz": 100.0},
    "all heights −100 m": {"dz": -100.0},
    "stopping: iterate to convergence": {"stopping": "converge"},
    "stopping rule threshold 0.03 %": {"rel": 3e-4},
    "stopping rule threshold 0.3 %": {"rel": 3e-3},
    "stopping rule threshold 1 %": {"rel": 1e-2},
    "angles: round radians 0.0015/0.0020/0.0025 (image 2)": {"_radians": True},
    "sign of the true error: truth − estimate": {"_sign": -1.0},
}


def _truth_in_radians() -> dict:
    T = G.images()
    T[2] = replace(T[2], phi=0.0015, omega=0.0020, kappa=0.0025)
    T[1] = replace(T[1], kappa=0.0025)
    return T


def run_choice(kw: dict) -> dict:
    """Fig. 8 test under one changed choice; returns column → task → outcome."""
    kw = dict(kw)
    sign = kw.pop("_sign", 1.0)
    if kw.pop("_radians", False):
        kw["truth"] = _truth_in_radians()
    with blas_threads(1):
        res = {c: fig8.run_surface(c, diagnose=False, **kw) for c in G.COLUMNS}
    if sign != 1.0:
        for per_task in res.values():
            for o in per_task.values():
                o.values = {q: (v if q == "m0" or q.startswith("r_") else sign * v)
                            for q, v in o.values.items()}  # fmt: skip
    return res


def sensitivity(choices: dict[str, dict] | None = None) -> list[dict]:
    """Counts of matching printed numbers per group under each choice.

    Returns
    -------
    list of dict
        ``{"choice", "calibration", "exterior", "other tasks"}`` with "k/n" strings.
    """
    out = []
    for name, kw in (choices or CHOICES).items():
        rows = rows_from_results(run_choice(kw or {}))
        c = {g: f"{k}/{n}" for g, _, k, n, _ in counts(rows)}
        out.append({"choice": name, **c})
    return out


def main() -> None:  # pragma: no cover - prints the table for the docs
    print("| choice | calibration | exterior | other tasks |")
    print("|---|---|---|---|")
    for r in sensitivity():
        print(f"| {r['choice']} | {r['calibration']} | {r['exterior']} | {r['other tasks']} |")


if __name__ == "__main__":  # pragma: no cover
    main()
