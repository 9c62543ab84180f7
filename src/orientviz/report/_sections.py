"""The content of an adjustment report, computed once for the text and the HTML form.

:func:`build_report` turns a solved problem into a :class:`Report`: an ordered list of
:class:`Section` objects, each with key/value lines, tables of already formatted cells,
the raw numbers behind them (``values``, plain floats and arrays) and the names of the
figures that belong to it. The renderers (:mod:`orientviz.report._text`,
:mod:`orientviz.report._html`) only lay this out; nothing here imports matplotlib.

Sections, in the order of a classic aerotriangulation protocol: ``summary``, ``sigma0``
(σ̂0 with its χ² test), ``redundancy``, ``parameters`` (transformation/interior
parameters of the small tasks), ``images`` (exterior orientation with precision),
``points`` (precision of the points), ``check`` (check-point differences), ``residuals``
(largest normalised residuals), ``correlations`` and ``warnings``. A section that does
not apply to a problem is left out (no check points → no ``check`` section).

Units of the report: σ of positions in mm when all of them are below 1 m, else in m;
σ of angles in mgon (files in gon), cc (files in c or cc), arc seconds (deg) or mrad
(rad); image residuals in µm; everything else in the units of the problem file.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..block import CHECK, CONTROL, TIE, block_layout
from ..io.problem import Problem
from ..io.solution import Solution
from ..plausibility import is_aerial
from ._coverage import coverage_below
from ._document import (
    R_LOW,
    Report,
    Section,
    Table,
    angle_unit,
    fmt,
    fmt_g,
)
from ._precision import PrecisionSections
from ._quality import QualitySections
from ._stats import (
    F64,
    block_of,
    chi2_test,
    image_coverage,
    image_slice,
    intersection_angles,
    used_observations,
)

__all__ = ["Report", "Section", "Table", "build_report", "chi2_test", "intersection_angles"]

#: Caption of the overview of a block that was not flown (a reconstruction's frame has no
#: up and no terrain: the plan view is its X-Y plane, without footprints).
CAPTION_PLAN = (
    "Plan view on the X-Y plane of the block's frame: projection centres, tie, control and "
    "check points (the block is not aerial: no image footprints on a terrain)."
)


# --------------------------------------------------------------------------- the builder
def build_report(
    problem: Problem,
    solution: Solution,
    *,
    largest: int = 10,
    correlation: float = 0.9,
    alpha: float = 0.05,
    worst: int = 10,
) -> Report:
    """Compute every section of the adjustment report.

    Parameters
    ----------
    problem : Problem
        The loaded problem (for file name, control/check coordinates and observations).
    solution : Solution
        Its solution from :func:`orientviz.io.solve.solve_problem`.
    largest : int
        Number of largest normalised residuals to list.
    correlation : float
        Threshold of ``|ρ|`` for the list of high correlations.
    alpha : float
        Significance level of the two-sided χ² test of σ̂0.
    worst : int
        Number of least precise points (and check points) listed by name.

    Returns
    -------
    Report
    """
    b = _Builder(problem, solution, largest, correlation, alpha, worst)
    return b.run()


def verdict_sections(
    problem: Problem, solution: Solution, *, alpha: float = 0.05, correlation: float = 0.9
) -> Report:
    """The sections ``sigma0``, ``residuals`` and ``warnings`` of :func:`build_report`.

    Their content equals that of the whole report's sections (the same warnings in the
    same order); the sections that only show numbers (summary, parameters, images,
    points, check points, the list of high correlations) are not formed, and the
    images' coverage is computed only where it may be below the warning's threshold.
    """
    b = _Builder(problem, solution, 10, correlation, alpha, 10)
    return b.run_verdict()


class _Builder(PrecisionSections, QualitySections):
    def __init__(self, problem, solution, largest, correlation, alpha, worst):
        self.p, self.s, self.adj = problem, solution, solution.adjustment
        self.largest, self.correlation, self.alpha, self.worst = largest, correlation, alpha, worst
        self.block = block_of(problem)
        self.warn: list[str] = []
        self.plot: dict[str, Any] = {}
        self.used = used_observations(self.adj)

    def coverage(self) -> F64:
        """:func:`image_coverage` of the block, computed once."""
        if not hasattr(self, "_coverage"):
            self._coverage = image_coverage(self.block)
        return self._coverage

    def coverage_below(
        self, threshold: float, first: int | None = None, among: NDArray[np.bool_] | None = None
    ) -> tuple[NDArray[np.bool_], F64]:
        """Which images' coverage is below ``threshold`` and the coverage (exact where it
        is below, or for the ``first`` of them among ``among``; :func:`coverage_below`
        unless :meth:`coverage` was computed)."""
        if hasattr(self, "_coverage"):
            return self._coverage < threshold, self._coverage
        return coverage_below(self.block, threshold, first=first, among=among)

    # .................................................................. driver
    def run(self) -> Report:
        secs = [
            self.summary(),
            self.sigma0(),
            self.redundancy(),
            self.parameters(),
            self.images(),
            self.points(),
            self.check(),
            self.residuals(),
            self.correlations(),
        ]
        self.geometry_warnings()
        secs.append(self.warnings())
        secs = [s for s in secs if s is not None]
        name = self.p.name or (os.path.basename(self.p.source) if self.p.source else "problem")
        title = f"Adjustment report: {name}"
        sub = f"{self.s.kind} · {self.s.method}" + (f" · {self.p.source}" if self.p.source else "")
        return Report(title=title, subtitle=sub, sections=secs, plot=self.plot)

    def run_verdict(self) -> Report:
        """The sections of :func:`verdict_sections`, their warnings as :meth:`run` forms them."""
        self.convergence_warning()
        secs = [self.sigma0()]
        self.redundancy()
        secs.append(self.residuals())
        self._near_singular_warnings(self._correlation_checks(with_pairs=False)[2])
        self.geometry_warnings()
        secs.append(self.warnings())
        return Report(title="", subtitle="", sections=secs, plot=self.plot)

    # .................................................................. summary
    def convergence_warning(self) -> None:
        adj = self.adj
        if not adj.converged:
            self.warn.append(
                f"the adjustment did not converge ({adj.reason}); the numbers "
                "below describe the last iteration"
            )

    def summary(self) -> Section:
        adj, s, p = self.adj, self.s, self.p
        counts = s.counts()  # n − u = r, as in the text and JSON outputs
        n_used, u, r = counts["observations"], counts["unknowns"], counts["redundancy"]
        n_excl = counts["not_adjusted"]["observations"]
        u_excl = counts["not_adjusted"]["parameters"]
        slices = adj.obs_slices
        pseudo = {k: sl.stop - sl.start for k, sl in slices.items() if k != "image"}
        n_constr = int(sum(pseudo.values()))
        blk = self.block
        v: dict[str, Any] = {
            "kind": s.kind,
            "method": s.method,
            "file": p.source or "",
            "name": p.name,
            "observations": n_used,
            "excluded": n_excl,
            "unknowns": u,
            "redundancy": r,
            "constraints": n_constr,
            "iterations": s.n_iterations,
            "converged": bool(adj.converged),
            "reason": adj.reason,
        }
        items = [("problem kind", s.kind), ("method", s.method)]
        if p.source:
            items.append(("file", p.source))
        if p.name:
            items.append(("name", p.name))
        if p.description:
            items.append(("description", p.description))
        if blk is not None:
            roles = blk.points.role
            n_tie, n_ctl, n_chk = (int(np.sum(roles == k)) for k in (TIE, CONTROL, CHECK))
            v.update(
                images=blk.n_images,
                points=blk.n_points,
                tie=n_tie,
                control=n_ctl,
                check=n_chk,
                rays=blk.n_observations,
                cameras=len(blk.cameras),
            )
            items += [
                ("cameras / images", f"{len(blk.cameras)} / {blk.n_images}"),
                ("points", f"{blk.n_points} ({n_tie} tie, {n_ctl} control, {n_chk} check)"),
                ("image points (rays)", str(blk.n_observations)),
            ]
        else:
            if s.image_ids:
                items.append(("images", str(len(s.image_ids))))
            if s.point_ids:
                items.append(("points", str(len(s.point_ids))))
        obs_txt = f"{n_used}"
        if n_excl:
            obs_txt += f" (+{n_excl} not adjusted: rays of check points or eliminated)"
        items.append(("observations n", obs_txt))
        if n_constr:
            items.append(
                (
                    "of which pseudo-observations",
                    ", ".join(f"{k} {n}" for k, n in pseudo.items() if n),
                )
            )
        u_txt = str(u) + (
            f" (+{u_excl} reported, not adjusted: fixed or computed afterwards)"
            if u_excl > 0
            else ""
        )
        if counts["conditions"]:
            u_txt += f"; {counts['conditions']} conditions"
        items += [
            ("unknowns u", u_txt),
            ("redundancy r", str(r)),
            ("datum", self.datum()),
            ("iterations", str(s.n_iterations)),
            (
                "convergence",
                ("converged" if adj.converged else "NOT CONVERGED") + f": {adj.reason}",
            ),
        ]
        u_ = s.units
        items.append(
            (
                "units of the file",
                f"length {u_.length_name}, image {u_.image}, angle "
                f"{u_.angle}; rotation sequence {s.sequence}",
            )
        )
        self.convergence_warning()
        sec = Section("summary", "Project summary", items=items, values=v)
        sec.text = [n for n in s.notes if not n.startswith(("check points", "block:"))]
        if blk is not None:
            sec.figures = ["overview"]
            self._overview_data()
            if not self.plot["overview"]["aerial"]:
                sec.values["captions"] = {"overview": CAPTION_PLAN}
        return sec

    def datum(self) -> str:
        blk, s = self.block, self.s
        if s.kind == "block" and blk is not None:
            free = bool(self.p.options.get("free", False))
            fix = self.p.options.get("fix") or []
            held = ", ".join([fix] if isinstance(fix, str) else map(str, fix))
            if free:  # control points are tie points: the datum is the held parameters
                if held:
                    return f"free network: {held} held at their given values"
                return "free network: minimum constraints (7 parameters held, named below)"
            sig = blk.points.sigma[blk.points.role == CONTROL]
            fixed = int(np.sum(sig == 0))
            weighted = int(np.sum(sig > 0))
            mode = self.p.options.get("control", "fixed")
            parts = [f"control points ({mode}): {fixed} fixed and {weighted} weighted coordinates"]
            if held and not fixed + weighted:
                parts = []
            n_gnss = int(np.sum(np.isfinite(blk.images.X0_sigma) & (blk.images.X0_sigma > 0)))
            if n_gnss:
                parts.append(f"{n_gnss} observed projection-centre coordinates")
            if held:
                parts.append(f"{held} held at their given values")
            return "; ".join(parts)
        return {
            "resection": "control points errorless (σ = 0)",
            "intersection": "image orientations held fixed as given",
            "similarity": "defined by the target coordinates of the control points",
            "pair": "dependent pair: left image and base component bx fixed",
            "radar": "as set by the radar task's fixed parameters",
        }.get(s.kind, "as defined by the problem kind")

    # .................................................................. sigma0
    def sigma0(self) -> Section:
        adj = self.adj
        r = int(adj.redundancy)
        t = chi2_test(float(adj.sigma0), r, self.alpha)
        items = [
            ("σ0 a posteriori (unit weight)", fmt(adj.sigma0, 4)),
            ("σ0 a priori", "1 (the observations' σ are absolute)"),
        ]
        v: dict[str, Any] = {"sigma0": float(adj.sigma0), "sigma0_prior": 1.0, "test": t}
        sl = image_slice(adj, self.s)
        img = np.zeros(adj.n_observations, bool)
        img[sl] = True
        img &= self.used
        if img.any() and self.s.observation_quantity == "image":
            s_img = float(np.median(adj.sigma_obs[img])) * 1000.0
            v["sigma_image_um"] = s_img
            v["sigma0_image_um"] = float(adj.sigma0) * s_img
            u = self.s.units  # a pixel file: in its pixels, not the nominal pixel size's µm
            f, iu = (1e-3 / u.pixel_size, "px") if u.image == "px" and u.pixel_size else (1.0, "µm")
            items.append(
                (
                    "σ0 a posteriori in the image",
                    f"{fmt(adj.sigma0 * s_img * f, 2)} {iu} "
                    f"(a priori σ of an image coordinate {fmt(s_img * f, 2)} {iu})",
                )
            )
        if t["accepted"] is None:
            items.append(("χ² test", "not possible (r = 0)"))
            self.warn.append("redundancy r = 0: the observations are not checked at all")
        else:
            items += [
                ("test statistic T = r · σ0² (a priori σ0 = 1)", f"{t['T']:.3f}"),
                (
                    f"χ²({r}) bounds at α = {self.alpha:g} (two-sided)",
                    f"[{t['lower']:.3f}, {t['upper']:.3f}]",
                ),
                (
                    "σ0 a posteriori accepted between",
                    f"{t['sigma0_lower']:.3f} and {t['sigma0_upper']:.3f}",
                ),
                (
                    "result",
                    "accepted: σ0 a posteriori agrees with the a-priori σ0"
                    if t["accepted"]
                    else (
                        "REJECTED: σ0 a posteriori too large — gross errors, systematic errors or "
                        "too optimistic a-priori σ"
                        if adj.sigma0 > 1
                        else "REJECTED: σ0 a posteriori too small — a-priori σ too pessimistic"
                    ),
                ),
            ]
            if not t["accepted"]:
                self.warn.append(
                    f"global test rejected: σ0 a posteriori = {adj.sigma0:.3f} outside "
                    f"[{t['sigma0_lower']:.3f}, {t['sigma0_upper']:.3f}]"
                )
        return Section("sigma0", "σ0 a posteriori and global test", items=items, values=v)

    # .................................................................. redundancy
    def redundancy(self) -> Section:
        adj = self.adj
        n = int(self.used.sum())
        r = int(adj.redundancy)
        v: dict[str, Any] = {"r": r, "n": n, "mean_r": r / n if n else float("nan")}
        items = [
            ("redundancy r", str(r)),
            ("observations n", str(n)),
            ("mean redundancy number r/n", fmt(v["mean_r"], 3)),
        ]
        ri = adj.redundancy_numbers
        tables = []
        if ri is not None:
            rr = ri[self.used]
            v.update(
                sum_ri=float(np.sum(rr)),
                min_ri=float(np.min(rr)) if rr.size else np.nan,
                n_low=int(np.sum(rr < R_LOW)),
            )
            items += [
                ("Σ r_i (equals r)", fmt(v["sum_ri"], 3)),
                ("smallest r_i", fmt_g(v["min_ri"], 3)),
                (f"observations with r_i < {R_LOW:g} (uncontrolled)", str(v["n_low"])),
            ]
            edges = [0.0, 0.01, R_LOW, 0.3, 0.5, 0.7, 1.0000001]
            cnt = np.histogram(rr, bins=edges)[0]
            tables.append(
                Table(
                    ["r_i", "observations", "share"],
                    [
                        [f"{a:g} … {min(b_, 1.0):g}", str(c), f"{100 * c / max(n, 1):.1f} %"]
                        for a, b_, c in zip(edges[:-1], edges[1:], cnt)
                    ],
                    title="distribution of r_i",
                )
            )
            v["ri_histogram"] = {"edges": edges, "counts": cnt}
            if v["n_low"]:
                idx = np.flatnonzero(self.used & (np.nan_to_num(ri, nan=1.0) < R_LOW))
                labels = [self.s.label(int(i)) for i in idx[:8]]
                self.warn.append(
                    f"{v['n_low']} observation(s) with redundancy number r_i < "
                    f"{R_LOW:g} are (nearly) uncontrolled: a gross error there "
                    f"would go undetected ({', '.join(labels)}" + (", …)" if idx.size > 8 else ")")
                )
        else:
            items.append(("redundancy numbers", "not computed by this method"))
        return Section("redundancy", "Redundancy", items=items, tables=tables, values=v)

    # .................................................................. parameters
    def parameters(self) -> Section | None:
        s = self.s
        if not s.parameters:
            return None
        rows, vals = [], []
        for par in s.parameters:
            f, un = s.factor(par.quantity), s.unit_name(par.quantity)
            if par.quantity == "angle":
                su, sf = angle_unit(s.units.angle)
                sig = par.sigma * sf
            else:
                su, sig = un, par.sigma * f
            sig_txt = "fixed" if sig == 0 else fmt_g(sig, 4)
            rows.append([par.name, fmt(par.value * f, 6), sig_txt, su or "—", un or "—"])
            vals.append(
                {
                    "name": par.name,
                    "value": par.value * f,
                    "unit": un,
                    "sigma": sig,
                    "sigma_unit": su,
                }
            )
        t = Table(["parameter", "value", "σ", "unit of σ", "unit of value"], rows, align="lrrll")
        return Section(
            "parameters", "Parameters and their precision", tables=[t], values={"parameters": vals}
        )

    # .................................................................. overview data
    def _overview_data(self) -> None:
        blk, s = self.block, self.s

        b2 = blk.copy()
        if s.image_ids and len(s.image_ids) == blk.n_images:
            b2.images.X0 = np.where(np.isfinite(s.X0), s.X0, b2.images.X0)
            b2.images.angles = np.where(np.isfinite(s.angles), s.angles, b2.images.angles)
        if len(s.point_ids) == blk.n_points:
            b2.points.xyz = np.where(np.isfinite(s.xyz), s.xyz, b2.points.xyz)
        foot = None
        ok_img = np.all(np.isfinite(b2.images.X0), axis=1) & np.all(
            np.isfinite(b2.images.angles), axis=1
        )
        aerial = is_aerial(b2, s.units.length)  # footprints on a terrain: a flown block's
        if aerial and ok_img.all() and np.any(np.isfinite(b2.points.xyz[:, 2])):
            with np.errstate(all="ignore"):
                Z = float(np.nanmean(b2.points.xyz[:, 2]))
                foot = block_layout(b2, height=Z).footprints
        self.plot["overview"] = {
            "X0": b2.images.X0,
            "footprints": foot,
            "xy": b2.points.xyz[:, :2],
            "role": np.asarray(blk.points.role),
            "ids_images": list(blk.images.ids),
            "length_unit": s.units.length_name,
            "aerial": aerial,
        }
