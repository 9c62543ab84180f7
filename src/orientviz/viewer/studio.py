"""The design studio (``orientviz view design``): plan a block and see its quality live.

The studio shows a planned block (:mod:`orientviz.design`): its points coloured by the
chosen quality measure of the design (σ_XY, σ_Z, the smallest redundancy number of the
point's rays, the largest MDB or δ̄0 of its rays), the control points as larger
triangles, the projection centres and strips. Every change of the control (make a point
control or tie, change its σ, accept the suggested point) goes through
:class:`orientviz.design.LiveDesign` (a low-rank update, no new factorisation); changes of
the plan (strips, images per strip, overlaps, image σ, control σ, GNSS) build the design
again. The scene and the panel (:mod:`orientviz.viewer.studio_panel`) show the legend, the summary next
to Ebner's accuracy laws, the weak spots in words, the list of changes and undo.

Scene tree::

    /design/points      every point, coloured by the measure
    /design/control     control points (larger black diamonds)
    /design/stations    projection centres
    /design/strips      the flight lines
    /design/suggested   the suggested next control point (when asked for)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..design import (
    DesignQuality,
    FlightDesign,
    LiveDesign,
    Suggestion,
    accuracy_law,
    design_block,
    suggest_control,
)
from .quality import STOPS
from .shapes import ramp

F64 = NDArray[np.float64]

#: measure key → (label, unit, scale to the unit, larger is worse)
MEASURES: dict[str, tuple[str, str, float, bool]] = {
    "sigma_xy": ("σ_XY of the point", "mm", 1e3, True),
    "sigma_z": ("σ_Z of the point", "mm", 1e3, True),
    "redundancy": ("smallest redundancy number of its rays", "", 1.0, False),
    "mdb": ("largest MDB of its rays", "µm", 1e3, True),
    "external": ("largest δ̄0 of its rays (external reliability)", "", 1.0, True),
}
#: colours of the scene's other elements
CONTROL_COLOUR = (20, 20, 20)
STATION_COLOUR = (90, 90, 160)
STRIP_COLOUR = (160, 160, 200)
SUGGESTED_COLOUR = (200, 0, 200)

#: the studio's first design: 4 strips of 10 images, XYZ control on the perimeter every 4 bases
START = FlightDesign(strips=4, images_per_strip=10, control="perimeter", control_spacing=4)


def point_values(q: DesignQuality, block, key: str) -> F64:
    """The measure ``key`` per point in the unit of :data:`MEASURES` (NaN: none)."""
    label, unit, f, _ = MEASURES[key]
    if key == "sigma_xy":
        return q.sigma_xy * f
    if key == "sigma_z":
        return q.point_sigma[:, 2] * f
    if key == "redundancy":
        return -q.per_point(-np.nanmin(q.redundancy, axis=1), block)
    if key == "mdb":
        return q.per_point(q.mdb, block) * f
    return q.per_point(q.external, block)


@dataclass
class Scale:
    """The colour scale of the measure: values ``lo`` … ``hi`` (unit), worse end red."""

    key: str
    lo: float
    hi: float

    def colours(self, values: F64) -> NDArray[np.uint8]:
        """RGB per value (grey for NaN, red for inf)."""
        worse_high = MEASURES[self.key][3]
        v = np.asarray(values, float)
        t = (v - self.lo) / max(self.hi - self.lo, 1e-300)
        if not worse_high:
            t = 1.0 - t
        t = np.where(np.isinf(v), 1.0, t)
        return ramp(np.clip(t, 0.0, 1.0), 1.0, STOPS)


def scale_of(values: F64, key: str) -> Scale:
    """A colour scale over the finite values (5th to 95th percentile … max)."""
    v = values[np.isfinite(values)]
    if v.size == 0:
        return Scale(key, 0.0, 1.0)
    lo, hi = float(v.min()), float(v.max())
    if hi - lo < 1e-12 * max(abs(hi), 1.0):
        hi = lo + 1.0
    return Scale(key, lo, hi)


def _fmt(v: float) -> str:
    return f"{v:,.0f}" if abs(v) >= 100 else f"{v:.3g}"


def legend_html(scale: Scale) -> str:
    """A colour bar with the measure's name and the values at its ends (HTML)."""
    label, unit, _, worse_high = MEASURES[scale.key]
    stops = STOPS if worse_high else STOPS[::-1]
    grad = ", ".join(f"rgb({int(r)},{int(gg)},{int(b)})" for r, gg, b in stops)
    u = f" {unit}" if unit else ""
    return (
        f'<div style="font-size:0.8em"><b>{label}</b>'
        f'<div style="height:12px;margin:3px 0;background:linear-gradient(to right, {grad})">'
        f'</div><div style="display:flex;justify-content:space-between">'
        f"<span>{_fmt(scale.lo)}{u}</span><span>{_fmt(scale.hi)}{u}</span></div>"
        f'<div><span style="color:rgb{CONTROL_COLOUR}">◆</span> control · '
        f'<span style="color:rgb{STATION_COLOUR}">■</span> projection centres · '
        f'<span style="color:rgb{SUGGESTED_COLOUR}">◆</span> suggested control</div></div>'
    )


class Studio:
    """The studio's state: the plan, the live design, the measure, the suggestion.

    No GUI here: :class:`~orientviz.viewer.studio_panel.StudioView` draws it and its panel
    edits it; the tests drive it directly.
    """

    def __init__(self, design: FlightDesign = START) -> None:
        self.measure = "sigma_z"
        self.suggestion: Suggestion | None = None
        self.plan_history: list[str] = []
        self.set_plan(design)

    def set_plan(self, design: FlightDesign) -> DesignQuality:
        """Build the design of a (new) plan: strips, overlaps, σ …"""
        self.design = design
        block, self.spec = design_block(design)
        self.live = LiveDesign(block, self.spec)
        self.law = accuracy_law(design, self.spec)
        self.suggestion = None
        return self.live.quality()

    @property
    def block(self):
        """The current design block."""
        return self.live.block

    @property
    def quality(self) -> DesignQuality:
        """The current quality."""
        return self.live.quality()

    def point_index(self, name: str) -> int:
        """Index of the point with id ``name`` (or an index as text)."""
        ids = self.block.points.ids
        if name in ids:
            return ids.index(name)
        try:
            k = int(name)
        except ValueError:
            raise ValueError(f"no point {name!r} (ids look like {ids[0]!r})") from None
        if not 0 <= k < len(ids):
            raise ValueError(f"no point {k}: the design has {len(ids)} points")
        return k

    def nearest_point(self, xy: F64) -> int:
        """The point nearest to a ground position (X, Y) in m."""
        d = np.linalg.norm(self.block.points.xyz[:, :2] - np.asarray(xy)[None, :2], axis=1)
        return int(np.argmin(d))

    def suggest(self, sigma: float) -> Suggestion:
        """Suggest the next control point (σ ``sigma`` m) for the shown measure: worst
        σ_XY, worst σ_Z (also for redundancy and MDB) or largest δ̄0."""
        crit = {"sigma_xy": "sigma_xy", "external": "external"}.get(self.measure, "sigma_z")
        self.suggestion = suggest_control(self.live, criterion=crit, sigma=sigma)
        return self.suggestion

    def values(self) -> F64:
        """The chosen measure per point."""
        return point_values(self.quality, self.block, self.measure)

    def summary_markdown(self) -> str:
        """The block's figures next to the accuracy law's values, the weak spots."""
        s = self.quality.summary
        law = self.law
        mm = 1e3

        def lawv(key):
            v = law.get(key, float("nan"))
            return "–" if not np.isfinite(v) else f"{v * mm:.1f}"

        d = self.design
        lines = [
            f"**{d.strips} strips × {d.images_per_strip} images**, 1:{d.scale:,.0f}, "
            f"p = {d.forward_overlap:.0%}, q = {d.side_overlap:.0%}, σ image "
            f"{d.sigma_image_mm * 1e3:.1f} µm, control σ {d.sigma_control * 100:.0f} cm, "
            f"{s['n_control']} control points"
            + (f", GNSS σ {d.sigma_gnss:.2f} m" if d.sigma_gnss else ""),
            "",
            "| | median | RMS | max | law (RMS) |",
            "| --- | --- | --- | --- | --- |",
            f"| σ_XY mm | {s['sigma_xy_median'] * mm:.1f} | {s['sigma_xy_rms'] * mm:.1f} | "
            f"{s['sigma_xy_max'] * mm:.1f} | {lawv('sigma_xy')} |",
            f"| σ_Z mm | {s['sigma_z_median'] * mm:.1f} | {s['sigma_z_rms'] * mm:.1f} | "
            f"{s['sigma_z_max'] * mm:.1f} | {lawv('sigma_z')} |",
            "",
            f"mean redundancy number {s['redundancy_mean']:.2f}; largest MDB "
            f"{s['mdb_max_mm'] * 1e3:.0f} µm; largest δ̄0 {s['external_max']:.1f}; "
            f"{s['untestable_rays']} rays not testable.  ",
            f"Law: {law.get('note', '')}",
        ]
        spots = self.quality.weak_spots
        if spots:
            lines += ["", "**Weak spots**"] + [f"- {w}" for w in spots]
        return "\n".join(lines)

    def changes_markdown(self) -> str:
        """The list of changes (plan and control) in order."""
        items = self.plan_history + self.live.history
        if not items:
            return "*no changes yet*"
        return "\n".join(f"{k + 1}. {t}" for k, t in enumerate(items[-12:]))
