"""The solution of a problem file: what ``orientviz solve`` prints, as text or as JSON.

Every problem kind (:mod:`orientviz.io.kinds`) returns a :class:`Solution`;
:mod:`orientviz.report` builds the full report from it (reports sit above ``io``).

Every number is converted to the units of the problem file: lengths in ``units.length``,
angles in ``units.angle``, image residuals in ``units.image``. Standard deviations are
a-posteriori (scaled with σ̂0) when the redundancy is positive, a-priori otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..adjust.result import W_CRITICAL, Adjustment
from .problem import Units
from .tables import json_number

F64 = NDArray[np.float64]


@dataclass
class Parameter:
    """A named estimate with its σ, in internal units, and what kind of quantity it is.

    ``quantity`` is ``"length"`` (m), ``"angle"`` (rad), ``"image"`` (mm) or ``"1"``
    (dimensionless, e.g. a scale factor).
    """

    name: str
    value: float
    sigma: float
    quantity: str


@dataclass
class Solution:
    """A solved problem, ready for reporting.

    Attributes
    ----------
    kind, method : str
        The problem kind and the method used (``"bundle"``, ``"resection"``, …).
    adjustment : Adjustment
        The solver's result.
    units : Units
        The problem file's units (reports use them).
    image_ids : list of str
        Images whose orientation was estimated (may be empty).
    X0, angles, X0_sigma, angles_sigma : ndarray, shape (m, 3)
        Projection centres (m) and ω, φ, κ (rad) with their σ.
    point_ids : list of str
        Points whose coordinates were estimated or transformed.
    xyz, xyz_sigma : ndarray, shape (p, 3)
        Point coordinates (m) and σ (m).
    point_roles : list of str
        Role of each point (tie/control/check/transformed).
    parameters : list of Parameter
        Other estimates (transformation parameters, …).
    observation_quantity : str
        Quantity of the observations (``"image"`` or ``"length"``), for residual units.
    critical : float
        Critical absolute normalised residual for flagging.
    notes : list of str
        Remarks for the report (e.g. check-point errors).
    iterations : int, optional
        Number of iterations when the adjustment's history does not hold them.
    verdict : dict, optional
        Global test, number of flagged observations and the warnings, as the report
        states them (:func:`orientviz.report.verdict`; ``orientviz solve`` sets it);
        printed by :meth:`as_text` and :meth:`as_dict` when set.
    start : Block, optional
        Frame kinds solved by the bundle: the block the adjustment started from
        (approximations computed, datum applied; the layout of ``adjustment.history``).
    """

    kind: str
    method: str
    adjustment: Adjustment
    units: Units
    sequence: str = "opk"
    image_ids: list[str] = field(default_factory=list)
    X0: F64 = field(default_factory=lambda: np.zeros((0, 3)))
    angles: F64 = field(default_factory=lambda: np.zeros((0, 3)))
    X0_sigma: F64 = field(default_factory=lambda: np.zeros((0, 3)))
    angles_sigma: F64 = field(default_factory=lambda: np.zeros((0, 3)))
    point_ids: list[str] = field(default_factory=list)
    xyz: F64 = field(default_factory=lambda: np.zeros((0, 3)))
    xyz_sigma: F64 = field(default_factory=lambda: np.zeros((0, 3)))
    point_roles: list[str] = field(default_factory=list)
    parameters: list[Parameter] = field(default_factory=list)
    observation_quantity: str = "image"
    critical: float = W_CRITICAL
    notes: list[str] = field(default_factory=list)
    iterations: int | None = None
    verdict: dict[str, Any] | None = None
    start: Any = None

    @property
    def n_iterations(self) -> int:
        """Iterations taken (the solver's own count if it gave one, else the history's)."""
        return int(self.adjustment.iterations if self.iterations is None else self.iterations)

    def counts(self) -> dict[str, int]:
        """Observations n, unknowns u and redundancy r of the adjustment as it ran.

        n − u = r always holds for them. Residuals and parameters that are reported but
        took no part in the adjustment (rays of independent check points, check points
        intersected afterwards, fixed points) are counted apart, under ``not_adjusted``.
        Solvers with conditions among the unknowns besides the observations report
        their number as ``conditions`` = r − (n − u) (0 for every solver of orientviz now).

        Returns
        -------
        dict
            ``observations``, ``unknowns``, ``redundancy``, ``conditions`` and
            ``not_adjusted`` = {``observations``, ``parameters``} (counts).
        """
        adj = self.adjustment
        r = int(adj.redundancy)
        n_all, u_all = int(adj.n_observations), int(adj.n_unknowns)
        ran = getattr(adj, "adjusted", None)
        if ran is not None:
            n, u = (int(k) for k in ran)
        else:
            rn = adj.redundancy_numbers
            n = n_all - (int(np.sum(~np.isfinite(rn))) if rn is not None else 0)
            u = u_all
        return {
            "observations": n,
            "unknowns": u,
            "redundancy": r,
            "conditions": r - (n - u),
            "not_adjusted": {"observations": n_all - n, "parameters": u_all - u},
        }

    def counts_text(self) -> str:
        """``"n observations, u unknowns, redundancy r"`` and what was not adjusted."""
        c = self.counts()
        out = f"{c['observations']} observations, {c['unknowns']} unknowns"
        if c["conditions"]:
            out += f", {c['conditions']} conditions"
        out += f", redundancy {c['redundancy']}"
        na = c["not_adjusted"]
        parts = []
        if na["observations"]:
            parts.append(f"{na['observations']} observations (rays of check points)")
        if na["parameters"] > 0:
            parts.append(f"{na['parameters']} parameters (fixed, or computed afterwards)")
        if parts:
            out += "; reported but not adjusted: " + ", ".join(parts)
        return out

    # ------------------------------------------------------------------ units
    def factor(self, quantity: str) -> float:
        """Multiply an internal value of ``quantity`` by this to get file units."""
        u = self.units
        return {
            "length": 1.0 / u.m_per_length,
            "angle": 1.0 / u.rad_per_angle,
            "image": 1.0 / u.mm_per_image,
            "1": 1.0,
        }[quantity]

    def unit_name(self, quantity: str) -> str:
        u = self.units
        return {"length": u.length_name, "angle": u.angle, "image": u.image, "1": ""}[quantity]

    def label(self, i: int) -> str:
        labels = self.adjustment.obs_labels
        return labels[i] if labels is not None and i < len(labels) else f"observation no. {i + 1}"

    def flagged(self) -> list[dict[str, Any]]:
        """Observations with abs(w) above ``critical``, largest first (file units)."""
        adj = self.adjustment
        f = self.factor(self.observation_quantity)
        out = []
        for i in adj.flagged(self.critical):
            out.append(
                {
                    "index": int(i),
                    "label": self.label(int(i)),
                    "v": json_number(adj.residuals[i] * f, 6),
                    "w": json_number(adj.normalized_residuals[i], 4),
                }
            )
        return out

    # ------------------------------------------------------------------ JSON
    def as_dict(self) -> dict[str, Any]:
        """The JSON report (see ``orientviz solve --json``)."""
        adj = self.adjustment
        L, A = self.factor("length"), self.factor("angle")
        num = json_number
        images = []
        for k, ident in enumerate(self.image_ids):
            X, a = self.X0[k] * L, self.angles[k] * A
            sX, sa = self.X0_sigma[k] * L, self.angles_sigma[k] * A
            images.append(
                {
                    "id": ident,
                    "X0": num(X[0]),
                    "Y0": num(X[1]),
                    "Z0": num(X[2]),
                    "omega": num(a[0]),
                    "phi": num(a[1]),
                    "kappa": num(a[2]),
                    "sigma": {
                        "X0": num(sX[0], 6),
                        "Y0": num(sX[1], 6),
                        "Z0": num(sX[2], 6),
                        "omega": num(sa[0], 6),
                        "phi": num(sa[1], 6),
                        "kappa": num(sa[2], 6),
                    },
                }
            )
        points = []
        for k, ident in enumerate(self.point_ids):
            X, s = self.xyz[k] * L, self.xyz_sigma[k] * L
            points.append(
                {
                    "id": ident,
                    "role": self.point_roles[k] if k < len(self.point_roles) else "",
                    "X": num(X[0]),
                    "Y": num(X[1]),
                    "Z": num(X[2]),
                    "sigma": {"X": num(s[0], 6), "Y": num(s[1], 6), "Z": num(s[2], 6)},
                }
            )
        params = [
            {
                "name": p.name,
                "value": num(p.value * self.factor(p.quantity)),
                "sigma": num(p.sigma * self.factor(p.quantity), 6),
                "unit": self.unit_name(p.quantity),
            }
            for p in self.parameters
        ]
        return {
            "kind": self.kind,
            "method": self.method,
            "units": self.units.as_dict(),
            "sequence": self.sequence,
            "sigma0": num(adj.sigma0, 17),  # full precision (issue #14)
            **self.counts(),
            "iterations": self.n_iterations,
            "converged": bool(adj.converged),
            "reason": adj.reason,
            "images": images,
            "points": points,
            "parameters": params,
            "flagged": self.flagged(),
            "critical": self.critical,
            **(
                {"global_test": self.verdict["global_test"], "warnings": self.verdict["warnings"]}
                if self.verdict is not None
                else {}
            ),
            "notes": list(self.notes),
        }

    # ------------------------------------------------------------------ text
    def as_text(self, largest: int = 5) -> str:
        """A readable report: σ0, redundancy, iterations, parameters ± σ, residuals."""
        adj = self.adjustment
        u = self.units
        L, A = self.factor("length"), self.factor("angle")
        lines = [
            f"{self.kind} ({self.method}): {self.counts_text()}",
            f"sigma0 = {adj.sigma0:.4g} (a-posteriori, unit weight)",
            f"{self.n_iterations} iteration{'' if self.n_iterations == 1 else 's'}, "
            f"{'converged' if adj.converged else 'NOT CONVERGED'}: {adj.reason}",
            f"units of the file: length {u.length_name}, image {u.image}, angle {u.angle}; "
            f"rotation sequence {self.sequence}",
        ]
        if self.parameters:
            lines.append("")
            lines.append("parameters:")
            width = max(12, *(len(p.name) for p in self.parameters))
            for p in self.parameters:
                f, un = self.factor(p.quantity), self.unit_name(p.quantity)
                lines.append(
                    f"  {p.name:{width}s} {_value_to_sigma(p.value * f, p.sigma * f):>16s}"
                    f" ± {p.sigma * f:.3g} {un}".rstrip()
                )
        if self.image_ids:
            lines.append("")
            lines.append(
                f"images (X0 Y0 Z0 ± σ [{u.length_name}], omega phi kappa ± σ [{u.angle}], "
                f"sequence {self.sequence}):"
            )
            for k, ident in enumerate(self.image_ids):
                X, s = self.X0[k] * L, self.X0_sigma[k] * L
                a, sa = self.angles[k] * A, self.angles_sigma[k] * A
                lines.append(f"  {ident:10s} " + " ".join(_pm(X[j], s[j], 4) for j in range(3)))
                if np.any(np.isfinite(a)):
                    lines.append(f"  {'':10s} " + " ".join(_pm(a[j], sa[j], 5) for j in range(3)))
        if self.point_ids:
            lines.append("")
            lines.append(f"points (X Y Z ± σ [{u.length_name}]):")
            shown = min(len(self.point_ids), 30)
            for k in range(shown):
                X, s = self.xyz[k] * L, self.xyz_sigma[k] * L
                role = self.point_roles[k] if k < len(self.point_roles) else ""
                lines.append(
                    f"  {self.point_ids[k]:10s} {role:11s} "
                    + " ".join(_pm(X[j], s[j], 4) for j in range(3))
                )
            if shown < len(self.point_ids):
                lines.append(f"  ... {len(self.point_ids) - shown} more (use --json for all)")
        qu = self.unit_name(self.observation_quantity)
        f = self.factor(self.observation_quantity)
        idx = adj.largest_residuals(largest)
        if idx.size:
            lines.append("")
            if adj.normalized_residuals is None:
                why = (
                    "the precision was not computed"  # e.g. points near infinity
                    if getattr(adj, "precision_error", None)
                    else "this method gives none"
                )
                lines.append(f"largest residuals (v [{qu}]; no redundancy numbers: {why}):")
            else:
                lines.append(f"largest normalised residuals (v [{qu}], w = v / (σ √r)):")
            w = adj.normalized_residuals
            for i in idx:
                wi = float("nan") if w is None else float(w[i])
                lines.append(
                    f"  {self.label(int(i)):24s} v = {adj.residuals[i] * f:10.4g}  w = {wi:7.2f}"
                )
        flagged = self.flagged()
        lines.append("")
        if flagged:
            lines.append(f"flagged (|w| > {self.critical:g}): {len(flagged)} observation(s)")
            for item in flagged[:20]:
                lines.append(f"  {item['label']:24s} w = {item['w']}")
        elif adj.normalized_residuals is None:  # no w: nothing was tested
            lines.append(f"flagged (|w| > {self.critical:g}): not tested (no redundancy numbers)")
        else:
            lines.append(f"flagged (|w| > {self.critical:g}): none")
        if self.verdict is not None:
            lines += _verdict_lines(self.verdict, float(adj.sigma0))
        for note in self.notes:
            if self.verdict is None or not note.startswith("warning: "):  # listed above
                lines.append(note)
        return "\n".join(lines)


def _verdict_lines(v: dict[str, Any], sigma0: float) -> list[str]:
    """The global test and the warnings as ``orientviz solve`` prints them."""
    t = v["global_test"]
    if t["result"] == "not possible":
        head = "global test: not possible (redundancy r = 0)"
    else:
        head = (
            f"global test (χ²({t['r']}), α = {t['alpha']:g}): {t['result'].upper()}: "
            f"σ0 = {sigma0:.3f} {'within' if t['result'] == 'accepted' else 'outside'} "
            f"[{t['sigma0_lower']:.3f}, {t['sigma0_upper']:.3f}]"
        )
        if t["result"] == "rejected":
            head += f" ({t['reason']})"
    lines = [head]
    if v["warnings"]:
        lines.append(f"warnings: {len(v['warnings'])}")
        lines += [f"  ! {k}. {m}" for k, m in enumerate(v["warnings"], 1)]
    else:
        lines.append("warnings: none")
    return lines


def _value_to_sigma(value: float, sigma: float) -> str:
    """A value printed to the digits its σ carries (σ to three significant digits).

    Fixed point while that needs at most 8 decimals, else scientific notation with
    as many mantissa digits as reach σ's third digit: a lens term of 2e-6 ± 1e-7
    prints as ``-1.998e-06``, not as ``-0.000002``.
    """
    if not np.isfinite(value):
        return "—"
    if not (np.isfinite(sigma) and sigma > 0):
        return f"{value:.6f}"
    decimals = max(0, 2 - int(np.floor(np.log10(sigma))))
    if decimals <= 8:
        return f"{value:.{decimals}f}"
    magnitude = int(np.floor(np.log10(abs(value)))) if value != 0 else 0
    mantissa = max(1, min(16, magnitude + decimals))  # 17 digits: all a double has
    return f"{value:.{mantissa}e}"


def _pm(value: float, sigma: float, digits: int) -> str:
    """``"  1234.5678 ±   0.0123"``; a value or σ that was not computed prints as a dash."""
    v = f"{value:13.{digits}f}" if np.isfinite(value) else f"{'—':>13s}"
    s = f"{sigma:8.{digits}f}" if np.isfinite(sigma) else f"{'—':>8s}"
    return f"{v} ±{s}"
