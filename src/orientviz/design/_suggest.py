"""Where to put the next control point: the candidate that most improves the worst value.

For a candidate point j made XYZ control with weights P = diag(1/σ²), the covariance of
every point k of the current design :class:`~orientviz.design.LiveDesign` becomes

    Q_kk' = Q_kk − Q_kj (P⁻¹ + Q_jj)⁻¹ Q_jk,

with the current columns Q_·j (:meth:`LiveDesign.current_columns`: the base design's
columns of j less the low-rank terms of the changes made so far). So each candidate costs its three columns and
a 3×3 update per point; the worst σ after the change is exact, not estimated. The
criterion ``"external"`` (the largest δ̄0 of any ray) needs the rays' redundancy and is
evaluated by making the change and taking it back (:meth:`LiveDesign.set_control`,
:meth:`LiveDesign.undo`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..blas import blas_threads
from ..block import TIE
from ..errors import InputError
from ._live_parts import _weights

F64 = NDArray[np.float64]

CRITERIA = ("sigma_z", "sigma_xy", "sigma", "external")


@dataclass
class Suggestion:
    """The proposed control point and what it gains.

    Attributes
    ----------
    point : int
        Index of the proposed point (a tie point of the current design).
    point_id : str
    criterion : str
        ``"sigma_z"``, ``"sigma_xy"``, ``"sigma"`` (largest of σ_X, σ_Y, σ_Z) — m — or
        ``"external"`` (largest δ̄0, dimensionless).
    before, after : float
        The worst value of the criterion over the non-control points now and with the
        proposed point as control.
    candidates : ndarray of int
        The points evaluated.
    values : ndarray
        The worst value after making each candidate control (same order).
    """

    point: int
    point_id: str
    criterion: str
    before: float
    after: float
    candidates: NDArray[np.int64]
    values: F64

    @property
    def gain(self) -> float:
        """before − after (units of the criterion)."""
        return self.before - self.after

    def describe(self) -> str:
        """The suggestion in words."""
        unit, f = ("", 1.0) if self.criterion == "external" else (" mm", 1e3)
        return (
            f"make point {self.point_id} control: worst {self.criterion} "
            f"{self.before * f:.1f}{unit} → {self.after * f:.1f}{unit} "
            f"({100 * self.gain / self.before:.0f} % better; {self.candidates.size} candidates)"
        )


def worst(sigma: F64, control: NDArray[np.bool_], criterion: str) -> float:
    """The worst value of a σ criterion (m) over the non-control points of (p, 3) σ."""
    s = sigma[~control]
    if criterion == "sigma_z":
        v = s[:, 2]
    elif criterion == "sigma_xy":
        v = np.sqrt(0.5 * (s[:, 0] ** 2 + s[:, 1] ** 2))
    else:
        v = s.max(axis=1)
    return float(np.nanmax(v)) if v.size else float("nan")


def _criterion_sigma(q, criterion):
    s = q.point_sigma
    if criterion == "sigma_z":
        return s[:, 2]
    if criterion == "sigma_xy":
        return q.sigma_xy
    return s.max(axis=1)


def suggest_control(
    live, *, criterion: str = "sigma_z", sigma: float = 0.02, candidates=None, top: int = 40
) -> Suggestion:
    """Propose the tie point whose making XYZ control most improves the worst value.

    Parameters
    ----------
    live : LiveDesign
        The current design.
    criterion : {"sigma_z", "sigma_xy", "sigma", "external"}
        What to improve: the largest σ_Z, σ_XY or σ of any coordinate (m) of the
        non-control points, or the largest δ̄0 of any ray.
    sigma : float
        σ of the new control point's coordinates, m.
    candidates : array_like of int, optional
        Points to try (default: every tie point when there are at most ``top`` of them,
        else the ``top`` tie points with the largest value of the criterion — control
        helps most where σ is largest).
    top : int
        Number of candidates chosen by default.

    Returns
    -------
    Suggestion
    """
    with blas_threads(getattr(live, "blas_threads", None)):
        return _suggest(live, criterion, sigma, candidates, top)


def _suggest(live, criterion, sigma, candidates, top) -> Suggestion:
    if criterion not in CRITERIA:
        raise InputError(f"criterion: expected one of {', '.join(CRITERIA)}, got {criterion!r}")
    if not sigma > 0:
        raise InputError(f"sigma: expected σ > 0 m, got {sigma}")
    q = live.quality()
    b = live.block
    ctrl = q.control
    tie = np.flatnonzero(b.points.role == TIE)
    if candidates is None:
        if tie.size <= top:
            cand = tie
        else:
            crit = q.per_point(q.external, b) if criterion == "external" else None
            if crit is None:
                crit = _criterion_sigma(q, criterion)
            crit = np.where(np.isfinite(crit), crit, np.inf)
            cand = tie[np.argsort(-crit[tie], kind="stable")[:top]]
    else:
        cand = np.asarray(candidates, np.int64)
    if cand.size == 0:
        raise InputError("no candidate points (every point is control)")
    if criterion == "external":  # make each change and take it back
        before = (
            q.summary["external_max"]
            if criterion == "external"
            else worst(q.point_sigma, ctrl, criterion)
        )
        vals = np.empty(cand.size)
        for k, j in enumerate(cand):
            qj = live.add_control(int(j), sigma)
            vals[k] = (
                qj.summary["external_max"]
                if criterion == "external"
                else worst(qj.point_sigma, qj.control, criterion)
            )
            live.undo()
            live.history = live.history[:-2]
    else:
        before = worst(q.point_sigma, ctrl, criterion)
        vals = _sigma_after(live, q, cand, sigma, criterion)
    best = int(np.argmin(vals))
    j = int(cand[best])
    return Suggestion(j, b.points.ids[j], criterion, before, float(vals[best]), cand, vals)


def _sigma_after(live, q, cand, sigma, criterion) -> F64:
    """The worst σ criterion after making each candidate control (exact, rank 3)."""
    w_now = _weights(live.block.points.sigma)
    Qp = q.point_cov  # current
    out = np.empty(cand.size)
    for k, j in enumerate(cand):
        Cj = live.current_columns(int(j))[1]  # (p, 3, 3)
        dw = 1.0 / sigma**2 - w_now[j]  # the weight added at j (3,)
        Gj = Cj[j]
        Mj = np.linalg.solve(np.eye(3) + dw[:, None] * Gj, np.diag(dw))
        Mj = 0.5 * (Mj + Mj.T)
        Qn = Qp - Cj @ Mj @ Cj.transpose(0, 2, 1)
        s = np.sqrt(np.clip(np.einsum("kii->ki", Qn), 0.0, None))
        c = q.control.copy()
        c[j] = True
        out[k] = worst(s, c, criterion)
    return out
