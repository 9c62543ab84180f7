"""DBAT's aerial block ``sxb``: orientviz's bundle beside DBAT's published report.

``orientviz reproduce dbat-sxb``. The data set (:mod:`orientviz.datasets.make_dbat`,
dataset ``dbat_sxb``) is adjusted the way DBAT's script ``data/script/sxb/sxb.xml``
does: interior orientation fixed at the camera's calibration (c = 123.9392 mm, no lens
distortion), 14 control points weighted by σ = 0.02, 0.02, 0.04 m, image coordinates
with σ = 0.5 px (marked points) and 1.0 px ("smart" tie points), and the two check
points 351 and 410 *keep their rays* while their given coordinates are withheld
(``options.check_points = "rays"``). The published numbers come from DBAT's own result
file shipped beside the data (``datasets/dbat/sxb/report.txt``), as printed.

What is compared (keys ``section|case|quantity``): σ0, σ0 in pixels, redundancy, the
numbers of parameters and observations, √(vᵀPv) (DBAT's "last error"), the overall
point RMS; per photo ω, φ, κ (deg), X0, Y0, Z0 (m), their standard deviations and the
correlations DBAT lists (over 95 %); the posterior coordinates and σ of the control and
check points; the check points' differences (posterior − given) and their max/RMS.

Definitions behind DBAT's derived numbers (read from its report): "Sigma0 (pixels)" is
σ0 times the a-priori σ of the marked points (0.5 px); "Overall point RMS" is the RMS
over image points of the residual length √(vx² + vy²) in pixels; "Last error" is
√(vᵀPv).
"""

from __future__ import annotations

import copy
from functools import lru_cache
from typing import Any

import numpy as np

from ..io.datasets import dataset_info, dataset_path, load_dataset
from ..io.kinds.block import solve
from . import Row
from .dbat_report import as_printed, predicted_rows, read_report, report_values, station_numbers

DATASET = "dbat_sxb"
#: the a-priori σ of the marked image points (px), DBAT's unit of "Sigma0 (pixels)"
MARK_SIGMA_PX = 0.5

#: the stopping tolerance of the reference run that shows which printed digits carry the
#: stopping rule (orientviz's default is 5e-3 of each parameter's conditional σ)
CONVERGED_TOL = 1e-9


def _report_path():
    return dataset_path(DATASET).parent / "sxb" / "report.txt"


def paper_values() -> dict[str, str | float]:
    """DBAT's published numbers as printed (strings; exponent notation as floats, see
    :func:`~orientviz.reproduce.dbat_report.as_printed`), keyed ``section|case|quantity``."""
    return copy.deepcopy(_published())


@lru_cache(maxsize=1)
def _published() -> dict[str, str | float]:
    return as_printed(report_values(read_report(_report_path())))[0]


@lru_cache(maxsize=1)
def _decimals() -> dict[str, int]:
    """Decimals of the numbers DBAT printed in exponent notation (from its report)."""
    return as_printed(report_values(read_report(_report_path())))[1]


@lru_cache(maxsize=2)
def _solution(tol: float | None = None):
    problem = load_dataset(DATASET)
    if tol is not None:
        problem.options = dict(problem.options, tol=tol, max_iter=50)
    return problem, solve(problem, "bundle")


def ours(tol: float | None = None) -> dict[str, float]:
    """orientviz's numbers for every key DBAT's report can hold (unrounded).

    ``tol`` None: ``orientviz solve dbat_sxb`` as shipped (default stopping rule);
    else the stopping tolerance (fraction of each parameter's conditional σ).
    """
    problem, sol = _solution(tol)
    adj = sol.adjustment
    block = problem.data
    info = dataset_info(DATASET)
    pixel = float(info["pixel_size_mm"])
    out: dict[str, float] = {
        "summary||sigma0": adj.sigma0,
        "summary||sigma0 [px]": adj.sigma0 * MARK_SIGMA_PX,
        "summary||redundancy": float(adj.redundancy),
        "summary||parameters": float(adj.n_unknowns),
        "summary||observations": float(adj.n_observations),
        "summary||sqrt(vTPv)": adj.sigma0 * np.sqrt(adj.redundancy),
    }
    n = len(block.observations)
    v = adj.residuals[: 2 * n].reshape(n, 2) / pixel
    out["residuals||overall point RMS [px]"] = float(np.sqrt(np.mean(np.sum(v**2, axis=1))))
    names = info["image_files"]  # DBAT's image number → file stem
    Q = adj.cofactor_groups["exterior"]
    for num, stem in names.items():
        i = list(sol.image_ids).index(stem)
        vals = np.r_[np.degrees(sol.angles[i]), sol.X0[i]]  # the Solution holds rad, m
        sig = np.r_[np.degrees(sol.angles_sigma[i]), sol.X0_sigma[i]]
        station_numbers(out, f"photo {num} ({stem}.jpg)", vals, sig, Q[i])
    labels = info["point_labels"]
    dxyz = []
    for p, pid in enumerate(sol.point_ids):
        role = sol.point_roles[p]
        if role not in ("control", "check"):
            continue
        case = f"point {pid} ({labels[pid]})"
        for a in range(3):
            A = "XYZ"[a]
            out[f"{role}|{case}|{A} [m]"] = float(sol.xyz[p, a])
            out[f"{role}|{case}|σ {A} [m]"] = float(sol.xyz_sigma[p, a])
        if role == "check":
            d = sol.xyz[p] - block.points.xyz_known[block.point_index(pid)]
            for name, val in zip(
                ("dX", "dY", "dZ", "dXY", "dXYZ"),
                (*d, np.hypot(d[0], d[1]), np.linalg.norm(d)),
            ):
                out[f"check differences|{case}|{name} [m]"] = float(val)
            dxyz.append(np.linalg.norm(d))
    if dxyz:
        out["check statistics||max 3-D difference [m]"] = float(np.max(dxyz))
        out["check statistics||RMS 3-D difference [m]"] = float(np.sqrt(np.mean(np.square(dxyz))))
    return out


def _shown(key: str, value: float) -> str:
    """orientviz's number for the terminal, one digit beyond DBAT's usual format."""
    q = key.rsplit("|", 1)[1]
    if q.startswith(("σ ", "correlation")) or key.startswith(("residuals", "summary||sigma0 [")):
        return f"{value:.5g}"
    if key.startswith("summary") and q in ("redundancy", "parameters", "observations"):
        return f"{value:.0f}"
    if key.startswith("stations"):
        return f"{value:.7f}"
    if key.startswith("summary"):
        return f"{value:.6f}"
    return f"{value:.4f}"


def table(*, paper: dict[str, Any] | None = None) -> list[Row]:
    """One row per published number of DBAT's sxb report, orientviz's value beside it."""
    paper = paper_values() if paper is None else paper
    mine, converged = ours(), ours(CONVERGED_TOL)
    return predicted_rows(
        paper, mine, _decimals(), _shown,
        lambda key, value: _stopping_note(key, paper[key], value, converged.get(key)),
    )  # fmt: skip


def _stopping_note(key: str, printed, value: float | None, converged: float | None) -> str:
    """Say so where the printed last digit depends on when the iterations stop.

    Compares orientviz's default run with a run to :data:`CONVERGED_TOL`: if the two
    round differently at the printed digits, the digit carries the stopping rule (DBAT
    stops once ‖J·p‖ ≤ 1e-6 ‖r‖; orientviz once every correction < 5e-3 of its σ).
    """
    if value is None or converged is None:
        return "not computed by orientviz"
    text = str(printed)
    decimals = _decimals().get(key, len(text.split(".")[1]) if "." in text else 0)
    if round(value, decimals) == round(converged, decimals):
        return ""
    return (
        f"last digit within the stopping rules: orientviz converged to {CONVERGED_TOL:g} σ "
        f"gives {_shown(key, converged)}, its default stop {_shown(key, value)}"
    )
