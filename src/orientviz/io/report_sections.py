"""The content of an adjustment report, computed once for the text and the HTML form.

:func:`build_report` turns a solved problem into a :class:`Report`: an ordered list of
:class:`Section` objects, each with key/value lines, tables of already formatted cells,
the raw numbers behind them (``values``, plain floats and arrays) and the names of the
figures that belong to it. The renderers (:mod:`orientviz.io.report_text`,
:mod:`orientviz.io.report_html`) only lay this out; nothing here imports matplotlib.

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

import math
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model import CHECK, CONTROL, TIE, Block
from ..units import RHO
from .problem import Problem
from .report import Solution

F64 = NDArray[np.float64]

#: Redundancy numbers below this mark an observation as (nearly) uncontrolled.
R_LOW: float = 0.1
#: Intersection angles below this (gon) are reported as weak.
SMALL_ANGLE_GON: float = 10.0
#: Images measured in fewer points than this are reported.
FEW_POINTS: int = 6
#: Images whose points cover less than this fraction of the format (convex hull) are reported.
POOR_COVERAGE: float = 0.25
#: A correlation matrix with a condition number above this is reported as near-singular.
NEAR_SINGULAR: float = 1e8
#: Tables list at most this many rows (worst first where a ranking exists).
MAX_ROWS: int = 200


# --------------------------------------------------------------------------- containers
@dataclass
class Table:
    """A table of formatted cells.

    Attributes
    ----------
    columns : list of str
        Column headings (units in brackets).
    rows : list of list of str
        Formatted cells, one list per row.
    title : str
        Heading above the table ("" for none).
    align : str
        One character per column, ``"l"`` or ``"r"``.
    marked : list of bool
        Rows to highlight (e.g. flagged residuals); empty = none.
    note : str
        A line under the table (e.g. "12 more rows not shown").
    """

    columns: list[str]
    rows: list[list[str]]
    title: str = ""
    align: str = ""
    marked: list[bool] = field(default_factory=list)
    note: str = ""

    def __post_init__(self) -> None:
        if not self.align:
            self.align = "l" + "r" * (len(self.columns) - 1)

    def as_dict(self) -> dict[str, Any]:
        return {
            "title": self.title,
            "columns": self.columns,
            "rows": self.rows,
            "marked": self.marked,
            "note": self.note,
        }


@dataclass
class Section:
    """One section of the report.

    Attributes
    ----------
    key : str
        Identifier (``"summary"``, ``"sigma0"``, …), also the HTML anchor.
    title : str
        Heading.
    items : list of (str, str)
        Key/value lines (label, formatted value).
    tables : list of Table
    text : list of str
        Free paragraphs (explanations, units).
    values : dict
        The raw numbers behind the section (floats, ints, arrays; internal or stated units).
    figures : list of str
        Names of the figures of :mod:`orientviz.plot.report_figures` for this section.
    """

    key: str
    title: str
    items: list[tuple[str, str]] = field(default_factory=list)
    tables: list[Table] = field(default_factory=list)
    text: list[str] = field(default_factory=list)
    values: dict[str, Any] = field(default_factory=dict)
    figures: list[str] = field(default_factory=list)


@dataclass
class Report:
    """The whole report: title, sections, warnings and the data of the figures.

    Attributes
    ----------
    title, subtitle : str
    sections : list of Section
    plot : dict
        Arrays for the figures (see :mod:`orientviz.plot.report_figures`), in m and the
        stated units.
    """

    title: str
    subtitle: str
    sections: list[Section]
    plot: dict[str, Any] = field(default_factory=dict)

    def section(self, key: str) -> Section | None:
        """The section called ``key``, or None if the report has none."""
        for s in self.sections:
            if s.key == key:
                return s
        return None

    @property
    def keys(self) -> list[str]:
        return [s.key for s in self.sections]

    @property
    def warnings(self) -> list[str]:
        s = self.section("warnings")
        return list(s.values.get("messages", [])) if s else []


# --------------------------------------------------------------------------- formatting
def fmt(value: float, digits: int = 3, width: int = 0) -> str:
    """A number with ``digits`` decimals, or a dash when it is not finite."""
    if value is None or not np.isfinite(value):
        return "—".rjust(width)
    return f"{value:{width}.{digits}f}"


def fmt_g(value: float, sig: int = 4) -> str:
    """A number with ``sig`` significant digits, or a dash."""
    if value is None or not np.isfinite(value):
        return "—"
    return f"{value:.{sig}g}"


def length_unit(sigmas_m: ArrayLike) -> tuple[str, float]:
    """``("mm", 1000)`` when every finite σ is below 1 m, else ``("m", 1)``."""
    a = np.asarray(sigmas_m, float)
    a = a[np.isfinite(a)]
    return ("mm", 1000.0) if a.size == 0 or np.max(a) < 1.0 else ("m", 1.0)


def angle_unit(file_unit: str) -> tuple[str, float]:
    """Unit and factor (per rad) for angle σ: mgon, cc, arc seconds or mrad."""
    if file_unit == "gon":
        return "mgon", RHO["gon"] * 1000.0
    if file_unit in ("c", "cc"):
        return "cc", RHO["cc"]
    if file_unit == "deg":
        return "arcsec", RHO["deg"] * 3600.0
    return "mrad", 1000.0


def _digits(scale_unit: str) -> int:
    return 1 if scale_unit in ("mm", "mgon", "cc", "arcsec", "mrad", "µm") else 3


# --------------------------------------------------------------------------- helpers
def _used(adj) -> NDArray[np.bool_]:
    """Observations that took part in the adjustment (finite redundancy number)."""
    if adj.redundancy_numbers is None:
        return np.ones(adj.n_observations, bool)
    return np.isfinite(adj.redundancy_numbers)


def _image_slice(adj, solution: Solution) -> slice:
    sl = adj.extra.get("obs_slices", {}).get("image") if isinstance(adj.extra, dict) else None
    if sl is not None:
        return sl
    return slice(0, adj.n_observations) if solution.observation_quantity == "image" else slice(0, 0)


def _split_label(label: str) -> tuple[str, str, str]:
    """(image, point, component) from labels such as ``img/pt/x``, ``pt/x`` or ``name``."""
    parts = label.split("/")
    if len(parts) >= 3:
        return parts[0], "/".join(parts[1:-1]), parts[-1]
    if len(parts) == 2:
        return "", parts[0], parts[1]
    return "", "", label


def chi2_test(sigma0: float, r: int, alpha: float = 0.05) -> dict[str, Any]:
    """Global test of σ̂0 against the a-priori σ0 = 1: T = r σ̂0² ~ χ²(r), two-sided.

    Returns a dict with ``T``, ``lower``/``upper`` (quantiles of χ²(r) at α/2 and
    1 − α/2), the corresponding bounds for σ̂0, ``alpha`` and ``accepted`` (None when
    r = 0 or σ̂0 is not finite).
    """
    from scipy.special import gammaincinv  # scipy.stats would take a second to import

    out: dict[str, Any] = {
        "alpha": alpha,
        "r": int(r),
        "T": float("nan"),
        "lower": float("nan"),
        "upper": float("nan"),
        "sigma0_lower": float("nan"),
        "sigma0_upper": float("nan"),
        "accepted": None,
    }
    if r <= 0 or not np.isfinite(sigma0):
        return out
    # quantile of χ²(r): P(r/2, x/2) = q  ⇔  x = 2 · P⁻¹(r/2, q)
    lo, hi = 2.0 * gammaincinv(r / 2, alpha / 2), 2.0 * gammaincinv(r / 2, 1 - alpha / 2)
    T = r * sigma0**2
    out.update(
        T=float(T),
        lower=float(lo),
        upper=float(hi),
        sigma0_lower=math.sqrt(lo / r),
        sigma0_upper=math.sqrt(hi / r),
        accepted=bool(lo <= T <= hi),
    )
    return out


def intersection_angles(block: Block, X0: F64, xyz: F64) -> F64:
    """Largest angle (rad) between two rays of each point; NaN for points with < 2 rays.

    Parameters
    ----------
    block : Block
        For the observations (which image sees which point).
    X0 : ndarray, shape (m, 3)
        Projection centres, m.
    xyz : ndarray, shape (p, 3)
        Point coordinates, m.
    """
    obs = block.observations
    out = np.full(block.n_points, np.nan)
    if len(obs) == 0:
        return out
    order = np.argsort(obs.point, kind="stable")
    pt = obs.point[order]
    d = xyz[pt] - X0[obs.image[order]]
    with np.errstate(invalid="ignore", divide="ignore"):
        d = d / np.linalg.norm(d, axis=1, keepdims=True)
    counts = np.bincount(pt, minlength=block.n_points)
    kmax = int(counts.max(initial=0))
    best = np.full(block.n_points, -np.inf)
    for off in range(1, kmax):
        same = pt[:-off] == pt[off:]
        if not same.any():
            break
        cosang = np.clip(np.einsum("ij,ij->i", d[:-off][same], d[off:][same]), -1.0, 1.0)
        ang = np.arccos(cosang)
        np.maximum.at(best, pt[:-off][same], ang)
    ok = np.isfinite(best)
    out[ok] = best[ok]
    return out


def image_coverage(block: Block) -> F64:
    """Area of the convex hull of each image's measured points over the format area (0…1)."""
    from scipy.spatial import ConvexHull, QhullError

    obs = block.observations
    cov = np.zeros(block.n_images)
    fmt_area = np.prod(block.cameras.format_mm[block.images.camera], axis=1)
    order = np.argsort(obs.image, kind="stable")
    starts = np.searchsorted(obs.image[order], np.arange(block.n_images + 1))
    for i in range(block.n_images):
        xy = obs.xy[order[starts[i] : starts[i + 1]]]
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        if xy.shape[0] < 3 or not fmt_area[i] > 0:
            continue
        try:
            cov[i] = ConvexHull(xy).volume / fmt_area[i]
        except (QhullError, ValueError):
            cov[i] = 0.0
    return cov


def _block_of(problem: Problem) -> Block | None:
    return problem.data if isinstance(problem.data, Block) else None


def _condition(C: F64) -> float:
    """Condition number of a correlation matrix (inf if singular)."""
    ev = np.linalg.eigvalsh(C)
    if not np.all(np.isfinite(ev)):
        return float("inf")
    return float(ev[-1] / ev[0]) if ev[0] > 0 else float("inf")


def _corr(Q: F64) -> F64:
    d = np.sqrt(np.clip(np.diag(Q), 1e-300, None))
    return Q / np.outer(d, d)


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


class _Builder:
    def __init__(self, problem, solution, largest, correlation, alpha, worst):
        self.p, self.s, self.adj = problem, solution, solution.adjustment
        self.largest, self.correlation, self.alpha, self.worst = largest, correlation, alpha, worst
        self.block = _block_of(problem)
        self.warn: list[str] = []
        self.plot: dict[str, Any] = {}
        self.used = _used(self.adj)

    def coverage(self) -> F64:
        """:func:`image_coverage` of the block, computed once."""
        if not hasattr(self, "_coverage"):
            self._coverage = image_coverage(self.block)
        return self._coverage

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

    # .................................................................. summary
    def summary(self) -> Section:
        adj, s, p = self.adj, self.s, self.p
        n_used = int(self.used.sum())
        n_excl = adj.n_observations - n_used
        r = int(adj.redundancy)
        u = n_used - r
        slices = adj.extra.get("obs_slices", {}) if isinstance(adj.extra, dict) else {}
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
        items += [
            ("unknowns u (= n − r)", str(u)),
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
                f"length {u_.length}, image {u_.image}, angle "
                f"{u_.angle}; rotation sequence {s.sequence}",
            )
        )
        if not adj.converged:
            self.warn.append(
                f"the adjustment did not converge ({adj.reason}); the numbers "
                "below describe the last iteration"
            )
        sec = Section("summary", "Project summary", items=items, values=v)
        sec.text = [n for n in s.notes if not n.startswith(("check points", "block:"))]
        if blk is not None:
            sec.figures = ["overview"]
            self._overview_data()
        return sec

    def datum(self) -> str:
        blk, s = self.block, self.s
        if s.kind == "block" and blk is not None:
            sig = blk.points.sigma[blk.points.role == CONTROL]
            fixed = int(np.sum(sig == 0))
            weighted = int(np.sum(sig > 0))
            mode = self.p.options.get("control", "fixed")
            txt = f"control points ({mode}): {fixed} fixed and {weighted} weighted coordinates"
            n_gnss = int(np.sum(np.isfinite(blk.images.X0_sigma) & (blk.images.X0_sigma > 0)))
            if n_gnss:
                txt += f"; {n_gnss} observed projection-centre coordinates"
            return txt
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
        sl = _image_slice(adj, self.s)
        img = np.zeros(adj.n_observations, bool)
        img[sl] = True
        img &= self.used
        if img.any() and self.s.observation_quantity == "image":
            s_img = float(np.median(adj.sigma_obs[img])) * 1000.0
            v["sigma_image_um"] = s_img
            v["sigma0_image_um"] = float(adj.sigma0) * s_img
            items.append(
                (
                    "σ0 a posteriori in the image",
                    f"{fmt(adj.sigma0 * s_img, 2)} µm "
                    f"(a priori σ of an image coordinate {fmt(s_img, 2)} µm)",
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
            rows.append([par.name, fmt(par.value * f, 6), fmt_g(sig, 4), su or "—", un or "—"])
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

    # .................................................................. images
    def images(self) -> Section | None:
        s = self.s
        if not s.image_ids:
            return None
        m = len(s.image_ids)
        sX = np.asarray(s.X0_sigma, float)
        sA = np.asarray(s.angles_sigma, float)
        lu, lf = length_unit(sX)
        au, af = angle_unit(s.units.angle)
        L, A = s.factor("length"), s.factor("angle")
        blk = self.block
        npts = np.full(m, -1)
        cov = np.full(m, np.nan)
        if blk is not None and len(blk.images) == m:
            npts = blk.points_per_image()
            cov = self.coverage()
        v = {
            "ids": list(s.image_ids),
            "sigma_X0": sX * lf,
            "sigma_angles": sA * af,
            "length_unit": lu,
            "angle_unit": au,
            "points": npts,
            "coverage": cov,
        }
        stats = []
        for j, nm in enumerate(("σX0", "σY0", "σZ0")):
            stats.append([nm, lu, *self._stat(sX[:, j] * lf, _digits(lu))])
        for j, nm in enumerate(("σω", "σφ", "σκ")):
            stats.append([nm, au, *self._stat(sA[:, j] * af, _digits(au))])
        t_stat = Table(
            ["", "unit", "mean", "r.m.s.", "max", "image of max"],
            stats,
            title="precision of the exterior orientation",
            align="llrrrl",
        )
        for row, col in zip(stats, range(6)):
            arr = (sX * lf if col < 3 else sA * af)[:, col % 3]
            row[-1] = s.image_ids[int(np.nanargmax(arr))] if np.any(np.isfinite(arr)) else "—"
        rank = np.argsort(-np.nan_to_num(np.linalg.norm(sX, axis=1), nan=-1.0))
        shown = rank[:MAX_ROWS] if m > MAX_ROWS else np.arange(m)
        rows = []
        dl = 3 if s.units.length == "m" else 1
        for k in shown:
            X = s.X0[k] * L
            a = s.angles[k] * A
            rows.append(
                [
                    s.image_ids[k],
                    *(fmt(x, dl) for x in X),
                    *(fmt(x, _digits(lu)) for x in sX[k] * lf),
                    *(fmt(x, 5) for x in a),
                    *(fmt(x, _digits(au)) for x in sA[k] * af),
                    str(npts[k]) if npts[k] >= 0 else "—",
                    f"{100 * cov[k]:.0f} %" if np.isfinite(cov[k]) else "—",
                ]
            )
        t = Table(
            [
                "image",
                f"X0 [{s.units.length}]",
                f"Y0 [{s.units.length}]",
                f"Z0 [{s.units.length}]",
                f"σX0 [{lu}]",
                f"σY0 [{lu}]",
                f"σZ0 [{lu}]",
                f"ω [{s.units.angle}]",
                f"φ [{s.units.angle}]",
                f"κ [{s.units.angle}]",
                f"σω [{au}]",
                f"σφ [{au}]",
                f"σκ [{au}]",
                "points",
                "coverage",
            ],
            rows,
            title="exterior orientation (adjusted) and its precision",
            note=(f"the {len(shown)} least precise of {m} images" if m > MAX_ROWS else ""),
        )
        sec = Section("images", "Per-image precision", tables=[t_stat, t], values=v)
        sec.text = [
            f"σ of positions in {lu}, of angles in {au} (a posteriori, scaled with "
            f"σ0 a posteriori); rotation sequence {s.sequence}. 'coverage' is the area of the "
            "convex hull of the image's measured points over the image format."
        ]
        if m >= 2 and np.any(np.isfinite(sX)):
            sec.figures = ["image_sigma"]
            self.plot["image_sigma"] = v
        return sec

    @staticmethod
    def _stat(a: F64, d: int) -> list[str]:
        a = a[np.isfinite(a)]
        if a.size == 0:
            return ["—", "—", "—", "—"]
        return [
            fmt(float(np.mean(a)), d),
            fmt(float(np.sqrt(np.mean(a**2))), d),
            fmt(float(np.max(a)), d),
            "",
        ]

    # .................................................................. points
    def points(self) -> Section | None:
        s = self.s
        if not s.point_ids:
            return None
        sxyz = np.asarray(s.xyz_sigma, float)
        roles = np.array(s.point_roles + [""] * (len(s.point_ids) - len(s.point_roles)))
        est = np.all(np.isfinite(sxyz), axis=1) & np.any(sxyz > 0, axis=1)
        if not est.any():
            return None
        lu, lf = length_unit(sxyz[est])
        d = _digits(lu)
        v: dict[str, Any] = {
            "ids": list(s.point_ids),
            "roles": list(roles),
            "sigma": sxyz * lf,
            "unit": lu,
            "estimated": est,
        }
        rows = []
        groups = [(r, est & (roles == r)) for r in dict.fromkeys(roles[est])]
        groups.append(("all", est))
        summary: dict[str, Any] = {}
        for name, sel in groups:
            if not sel.any() or (name == "all" and len(groups) == 2):
                continue
            a = sxyz[sel] * lf
            rms = np.sqrt(np.mean(a**2, axis=0))
            mx = np.max(a, axis=0)
            summary[name] = {"n": int(sel.sum()), "rms": rms, "max": mx}
            rows.append(
                [name, str(int(sel.sum())), *(fmt(x, d) for x in rms), *(fmt(x, d) for x in mx)]
            )
        v["summary"] = summary
        t1 = Table(
            [
                "points",
                "n",
                f"r.m.s. σX [{lu}]",
                f"r.m.s. σY [{lu}]",
                f"r.m.s. σZ [{lu}]",
                f"max σX [{lu}]",
                f"max σY [{lu}]",
                f"max σZ [{lu}]",
            ],
            rows,
            title="summary of the point precision (estimated points)",
        )
        total = np.where(est, np.sqrt(np.nansum(sxyz**2, axis=1)), -1.0)
        worst = np.argsort(-total)[: min(self.worst, int(est.sum()))]
        rays = self.block.rays_per_point() if self.block is not None else None
        L = s.factor("length")
        rows2 = []
        for k in worst:
            rows2.append(
                [
                    s.point_ids[k],
                    roles[k],
                    *(fmt(x, 3) for x in s.xyz[k] * L),
                    *(fmt(x, d) for x in sxyz[k] * lf),
                    str(rays[k]) if rays is not None and k < len(rays) else "—",
                ]
            )
        t2 = Table(
            [
                "point",
                "role",
                f"X [{s.units.length}]",
                f"Y [{s.units.length}]",
                f"Z [{s.units.length}]",
                f"σX [{lu}]",
                f"σY [{lu}]",
                f"σZ [{lu}]",
                "rays",
            ],
            rows2,
            title=f"the {len(worst)} least precise points",
            align="llrrrrrrr",
        )
        v["worst"] = [s.point_ids[k] for k in worst]
        sec = Section("points", "Per-point precision", tables=[t1, t2], values=v)
        sec.text = [
            f"a-posteriori σ in {lu}; control points held fixed have σ = 0 and are not "
            "counted; all coordinates: orientviz solve FILE --json"
        ]
        if self.block is not None and np.any(np.isfinite(s.xyz[est])):
            sec.figures = ["point_precision"]
            self.plot["point_precision"] = {
                "xy": s.xyz[est, :2],
                "sigma": sxyz[est] * lf,
                "unit": lu,
            }
        return sec

    # .................................................................. check points
    def check(self) -> Section | None:
        blk, s = self.block, self.s
        if blk is None:
            return None
        chk = np.flatnonzero(
            (blk.points.role == CHECK) & np.any(np.isfinite(blk.points.xyz_known), axis=1)
        )
        if chk.size == 0:
            return None
        pos = {k: i for i, k in enumerate(s.point_ids)}
        ids = [blk.points.ids[i] for i in chk]
        have = np.array([i in pos for i in ids])
        est = np.full((chk.size, 3), np.nan)
        est[have] = s.xyz[[pos[i] for i, h in zip(ids, have) if h]]
        dm = est - blk.points.xyz_known[chk]
        n = np.sum(np.isfinite(dm), axis=0)
        with np.errstate(invalid="ignore"):
            rms = np.sqrt(np.nansum(dm**2, axis=0) / np.maximum(n, 1))
            mean = np.nansum(dm, axis=0) / np.maximum(n, 1)
            mx = np.nanmax(np.abs(np.where(np.isfinite(dm), dm, -np.inf)), axis=0)
        rms = np.where(n > 0, rms, np.nan)
        mean = np.where(n > 0, mean, np.nan)
        mx = np.where(n > 0, mx, np.nan)
        lu, lf = length_unit(np.abs(dm))
        d = _digits(lu)
        v: dict[str, Any] = {
            "ids": ids,
            "difference_m": dm,
            "rms_m": rms,
            "mean_m": mean,
            "max_abs_m": mx,
            "n": n,
            "unit": lu,
        }
        items = [
            (
                "check points",
                f"{chk.size} ({int(np.sum(np.all(np.isfinite(dm), axis=1)))} "
                "with estimated coordinates)",
            )
        ]
        rows = [
            ["μ (r.m.s.)", *(fmt(x * lf, d) for x in rms)],
            ["mean", *(fmt(x * lf, d) for x in mean)],
            ["max abs", *(fmt(x * lf, d) for x in mx)],
            ["n", *(str(int(x)) for x in n)],
        ]
        t1 = Table(
            ["", f"X [{lu}]", f"Y [{lu}]", f"Z [{lu}]"],
            rows,
            title="differences estimated − given at the check points",
        )
        tables = [t1]
        scale = self._image_scale()
        s0i = self._sigma0_image_mm()
        if scale is not None and s0i is not None and s0i > 0:
            ratio = rms / scale * 1000.0 / s0i  # m in the object → mm in the image
            v.update(image_scale=scale, mu_over_sigma0=ratio)
            items.append(("image scale 1 : m_b", f"1 : {scale:,.0f}".replace(",", " ")))
            items.append(
                (
                    "μ/σ0 in image scale (μ / m_b / σ0 in the image)",
                    ", ".join(f"{a} {fmt(x, 2)}" for a, x in zip("XYZ", ratio)),
                )
            )
            items.append(
                (
                    "μ in the image (μ / m_b)",
                    ", ".join(f"{a} {fmt(x / scale * 1e6, 2)} µm" for a, x in zip("XYZ", rms)),
                )
            )
            items.append(("σ0 a posteriori in the image", f"{fmt(s0i * 1000, 2)} µm"))
        order = np.argsort(-np.nan_to_num(np.linalg.norm(dm, axis=1), nan=-1.0))
        rows2 = [
            [
                ids[k],
                *(fmt(x * lf, d) for x in dm[k]),
                fmt(float(np.linalg.norm(dm[k, :2])) * lf, d),
            ]
            for k in order[:MAX_ROWS]
        ]
        tables.append(
            Table(
                ["point", f"ΔX [{lu}]", f"ΔY [{lu}]", f"ΔZ [{lu}]", f"ΔXY [{lu}]"],
                rows2,
                title="check points, largest difference first",
            )
        )
        sec = Section("check", "Check-point statistics", items=items, tables=tables, values=v)
        sec.text = [
            "Check points take no part in the adjustment: they are intersected from the "
            "adjusted orientations and compared with their given coordinates."
        ]
        self.plot["check"] = {"xy": blk.points.xyz_known[chk, :2], "d": dm}
        return sec

    def _image_scale(self) -> float | None:
        blk, s = self.block, self.s
        if blk is None or not s.image_ids or len(blk.cameras) == 0:
            return None
        Z0 = np.asarray(s.X0, float)[:, 2]
        zg = np.nanmean(np.asarray(s.xyz, float)[:, 2]) if len(s.point_ids) else np.nan
        c = float(np.mean(blk.cameras.c)) / 1000.0
        h = float(np.nanmean(Z0) - zg)
        if not np.isfinite(h) or h <= 0 or c <= 0:
            return None
        return h / c

    def _sigma0_image_mm(self) -> float | None:
        adj = self.adj
        sl = _image_slice(adj, self.s)
        img = np.zeros(adj.n_observations, bool)
        img[sl] = True
        img &= self.used
        if not img.any() or self.s.observation_quantity != "image":
            return None
        return float(adj.sigma0) * float(np.median(adj.sigma_obs[img]))

    # .................................................................. residuals
    def residuals(self) -> Section:
        adj, s = self.adj, self.s
        w = adj.normalized_residuals
        k = self.largest
        img_q = s.observation_quantity == "image"
        vu = "µm" if img_q else s.unit_name(s.observation_quantity)
        vf = 1000.0 if img_q else s.factor(s.observation_quantity)
        blk = self.block
        block_obs = (
            blk is not None
            and s.kind == "block"
            and adj.extra.get("obs_slices", {}).get("image") is not None
        )
        rows, marked, recs = [], [], []
        idx = adj.largest_residuals(k)
        for i in idx:
            i = int(i)
            lab = s.label(i)
            if block_obs and i < 2 * blk.n_observations:
                o = i // 2
                im, pt, comp = (
                    blk.images.ids[blk.observations.image[o]],
                    blk.points.ids[blk.observations.point[o]],
                    "xy"[i % 2],
                )
            else:
                im, pt, comp = _split_label(lab)
                if not im and len(s.image_ids) == 1 and s.kind != "similarity":
                    im = s.image_ids[0]
            ri = float(adj.redundancy_numbers[i]) if adj.redundancy_numbers is not None else np.nan
            wi = float(w[i]) if w is not None else np.nan
            flag = bool(np.isfinite(wi) and abs(wi) > s.critical)
            rec = {
                "index": i,
                "label": lab,
                "image": im,
                "point": pt,
                "component": comp,
                "v": float(adj.residuals[i]) * vf,
                "sigma": float(adj.sigma_obs[i]) * vf,
                "r": ri,
                "w": wi,
                "flagged": flag,
            }
            recs.append(rec)
            rows.append(
                [
                    str(i),
                    lab,
                    im or "—",
                    pt or "—",
                    comp,
                    fmt(rec["v"], 2),
                    fmt(rec["sigma"], 2),
                    fmt(ri, 3) if not ri < 1e-3 else fmt_g(ri, 2),
                    fmt(wi, 2),
                    "> crit" if flag else "",
                ]
            )
            marked.append(flag)
        n_flag = int(adj.flagged(s.critical).size)
        items = [
            ("critical value of |w|", f"{s.critical:g} (Baarda's w-test)"),
            ("observations above it", str(n_flag)),
        ]
        if w is None:
            items.append(
                ("normalised residuals", "not available (no redundancy numbers); ranked by |v|")
            )
        t = Table(
            ["obs", "label", "image", "point", "coord", f"v [{vu}]", f"σ [{vu}]", "r_i", "w", ""],
            rows,
            title=f"the {len(rows)} largest normalised residuals",
            align="rlllcrrrrl",
            marked=marked,
        )
        v: dict[str, Any] = {
            "largest": recs,
            "n_flagged": n_flag,
            "critical": s.critical,
            "unit": vu,
        }
        if n_flag:
            self.warn.append(
                f"{n_flag} observation(s) with |w| > {s.critical:g}: possible gross "
                f"errors (largest: {recs[0]['label']}, w = {recs[0]['w']:.2f})"
            )
        sec = Section(
            "residuals", "Largest normalised residuals", items=items, tables=[t], values=v
        )
        sec.text = [
            "w_i = v_i / (σ_i √r_i): the residual divided by its own standard deviation "
            "(Baarda's data snooping, a-priori σ0 = 1); 'obs' is the position in the "
            "observation vector."
        ]
        if w is not None:
            ww = w[self.used & np.isfinite(w)]
            if ww.size:
                sec.figures = ["w_histogram"]
                self.plot["w_histogram"] = {"w": ww, "critical": s.critical}
        return sec

    # .................................................................. correlations
    def correlations(self) -> Section:
        adj, thr = self.adj, self.correlation
        pairs: list[tuple[str, str, float]] = []
        scope = ""
        near: list[tuple[str, float]] = []
        free = np.isfinite(adj.std()) & (adj.std() > 0)
        if adj.cofactor is not None:
            scope = "all pairs of parameters"
            idx = np.flatnonzero(free)
            if idx.size:
                C = _corr(adj.cofactor[np.ix_(idx, idx)])
                i, j = np.triu_indices_from(C, k=1)
                sel = np.abs(C[i, j]) > thr
                pairs = sorted(
                    (
                        (adj.names[idx[a]], adj.names[idx[b]], float(C[a, b]))
                        for a, b in zip(i[sel], j[sel])
                    ),
                    key=lambda t: -abs(t[2]),
                )
                cond = _condition(C)
                if cond > NEAR_SINGULAR:
                    near.append(("all parameters", cond))
        else:
            scope = (
                "pairs within one image's or one point's parameters (the full cofactor "
                "matrix is not formed for blocks)"
            )
            for bname, Q in adj.cofactor_blocks.items():
                if bname not in adj.blocks or Q.ndim != 3:
                    continue
                names = adj.names[adj.blocks[bname]]
                nb = Q.shape[1]
                fb = free[adj.blocks[bname]].reshape(-1, nb)
                # parameters without a σ (fixed points) get unit variance and no correlation
                d = np.sqrt(np.clip(np.einsum("kii->ki", Q), 0.0, None))
                d = np.where(fb & (d > 0), d, 1.0)
                C = np.where(
                    fb[:, :, None] & fb[:, None, :], Q / (d[:, :, None] * d[:, None, :]), 0.0
                )
                C[:, np.arange(nb), np.arange(nb)] = 1.0
                i, j = np.triu_indices(nb, k=1)
                kk, pp = np.nonzero(np.abs(C[:, i, j]) > thr)
                for k, q in zip(kk, pp):
                    pairs.append(
                        (names[k * nb + i[q]], names[k * nb + j[q]], float(C[k, i[q], j[q]]))
                    )
                active = np.flatnonzero(fb.sum(axis=1) >= 2)
                if active.size:
                    with np.errstate(all="ignore"):
                        ev = np.linalg.eigvalsh(C[active])
                    cond = np.where(
                        ev[:, 0] > 0, ev[:, -1] / np.where(ev[:, 0] > 0, ev[:, 0], 1.0), np.inf
                    )
                    for k in active[np.flatnonzero(~(cond <= NEAR_SINGULAR))]:
                        near.append(
                            (names[k * nb].split(".")[0], float(cond[np.searchsorted(active, k)]))
                        )
            pairs.sort(key=lambda t: -abs(t[2]))
        for what, cond in near[:10]:
            self.warn.append(
                f"near-singular: the correlation matrix of {what} has condition "
                f"number {cond:.3g} (> {NEAR_SINGULAR:.0e}); parameters nearly "
                "undetermined"
            )
        rows = [[a, b, f"{r:+.4f}"] for a, b, r in pairs[:MAX_ROWS]]
        t = Table(
            ["parameter", "parameter", "ρ"],
            rows,
            align="llr",
            title=f"pairs with |ρ| > {thr:g}",
            note=(f"{len(pairs) - MAX_ROWS} more not shown" if len(pairs) > MAX_ROWS else ""),
        )
        items = [
            ("threshold", f"|ρ| > {thr:g}"),
            ("scope", scope),
            ("pairs above the threshold", str(len(pairs))),
        ]
        sec = Section(
            "correlations",
            "High correlations",
            items=items,
            tables=[t] if rows else [],
            values={"pairs": pairs, "threshold": thr},
        )
        if any(
            {a.split(".")[-1], b.split(".")[-1]} in ({"X0", "phi"}, {"Y0", "omega"})
            for a, b, _ in pairs
        ):
            sec.text = [
                "X0–φ and Y0–ω are strongly correlated in every near-vertical image: "
                "a shift of the projection centre and a tilt move the image almost "
                "alike. This is expected and no defect."
            ]
        return sec

    # .................................................................. warnings
    def warnings(self) -> Section:
        msgs = list(dict.fromkeys(self.warn))
        sec = Section("warnings", "Warnings on geometry and quality", values={"messages": msgs})
        sec.items = [("warnings", str(len(msgs)) if msgs else "none")]
        sec.text = [
            f"Checked: convergence, global test, |w| above the critical value, redundancy "
            f"numbers below {R_LOW:g}, tie/check points with fewer than 3 rays, intersection "
            f"angles below {SMALL_ANGLE_GON:g} gon, images with fewer than {FEW_POINTS} points or "
            f"points covering less than {POOR_COVERAGE:.0%} of the format, near-singular "
            f"correlation matrices (condition number above {NEAR_SINGULAR:.0e})."
        ]
        return sec

    # .................................................................. geometry
    def geometry_warnings(self) -> None:
        blk, s = self.block, self.s
        if blk is None:
            return
        rays = blk.rays_per_point()
        roles = blk.points.role
        if s.kind != "resection":
            weak = np.flatnonzero((roles != CONTROL) & (rays < 3))
            if weak.size:
                self.warn.append(
                    f"{weak.size} tie/check point(s) with fewer than 3 rays: no "
                    "gross-error check along the ray (" + self._names(blk.points.ids, weak) + ")"
                )
            X0 = blk.images.X0
            if s.image_ids and len(s.image_ids) == blk.n_images:
                X0 = np.where(np.isfinite(s.X0), s.X0, X0)
            xyz = blk.points.xyz
            if len(s.point_ids) == blk.n_points:
                xyz = np.where(np.isfinite(s.xyz), s.xyz, xyz)
            ang = intersection_angles(blk, X0, xyz) * RHO["gon"]
            small = np.flatnonzero(np.isfinite(ang) & (ang < SMALL_ANGLE_GON))
            self.plot.setdefault("geometry", {})["angles_gon"] = ang
            if small.size:
                self.warn.append(
                    f"{small.size} point(s) with intersection angle below "
                    f"{SMALL_ANGLE_GON:g} gon: weak height ("
                    + self._names(blk.points.ids, small, ang, "gon")
                    + ")"
                )
        if s.image_ids and len(s.image_ids) == blk.n_images:
            npts = blk.points_per_image()
            few = np.flatnonzero(npts < FEW_POINTS)
            if few.size:
                self.warn.append(
                    f"{few.size} image(s) measured in fewer than {FEW_POINTS} "
                    "points (" + self._names(blk.images.ids, few, npts, "points") + ")"
                )
            cov = self.coverage()
            poor = np.flatnonzero((cov < POOR_COVERAGE) & (npts >= 3))
            if poor.size:
                self.warn.append(
                    f"{poor.size} image(s) whose points cover less than "
                    f"{POOR_COVERAGE:.0%} of the format: poorly determined "
                    "orientation (" + self._names(blk.images.ids, poor, cov * 100, "%") + ")"
                )
        std = self.adj.std()
        bad = ~np.isfinite(std)
        if s.kind == "block" and "points" in self.adj.blocks:
            pb = self.adj.blocks["points"]
            nb = bad[pb].reshape(-1, 3)
            nb[roles == CHECK] = False  # check points are not unknowns
            bad[pb] = nb.reshape(-1)
        if np.any(bad) and s.method == "bundle":
            names = [self.adj.names[i] for i in np.flatnonzero(bad)[:5]]
            self.warn.append(
                f"{int(bad.sum())} parameter(s) without a computed σ ({', '.join(names)})"
            )

    @staticmethod
    def _names(ids, idx, val=None, unit="", k: int = 6) -> str:
        parts = [ids[i] + (f" {val[i]:.3g} {unit}" if val is not None else "") for i in idx[:k]]
        return ", ".join(parts) + (", …" if len(idx) > k else "")

    # .................................................................. overview data
    def _overview_data(self) -> None:
        blk, s = self.block, self.s
        from ..block.layout import block_layout

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
        if ok_img.all() and np.any(np.isfinite(b2.points.xyz[:, 2])):
            with np.errstate(all="ignore"):
                Z = float(np.nanmean(b2.points.xyz[:, 2]))
                foot = block_layout(b2, height=Z).footprints
        self.plot["overview"] = {
            "X0": b2.images.X0,
            "footprints": foot,
            "xy": b2.points.xyz[:, :2],
            "role": np.asarray(blk.points.role),
            "ids_images": list(blk.images.ids),
        }
