"""The design studio (``orientviz view design``): plan a block and see its quality live.

The studio shows a planned block (:mod:`orientviz.design`): its points coloured by the
chosen quality measure of the design (σ_XY, σ_Z, the smallest redundancy number of the
point's rays, the largest MDB or δ̄0 of its rays), the control points as larger
triangles, the projection centres and strips. Every change of the control (make a point
control or tie, change its σ, accept the suggested point) and of the images (add, remove,
move an image; cross strips and removed strips, which are new designs when the step would
be too wide) goes through :class:`orientviz.design.LiveDesign` (a low-rank update, no new
factorisation); changes of the plan (strips, images per strip, overlaps, image σ, control
σ, GNSS) build the design again, Ebner's accuracy law only for a new layout. Under the
independent-models method (:class:`orientviz.design.LiveModels`, one factorisation per
structure) the bundle's update of a structural change waits until the bundle is shown
(:mod:`orientviz.viewer.studio_live`). The scene and the panel
(:mod:`orientviz.viewer.studio_panel`) show the legend, the summary next to Ebner's
accuracy laws (:mod:`orientviz.viewer.studio_text`), the weak spots in words, the list of
changes and undo.

Scene tree::

    /design/points      every point, coloured by the measure
    /design/control     control points (larger black diamonds)
    /design/stations    projection centres
    /design/strips      the flight lines
    /design/suggested   the suggested next control point (when asked for)
"""

from __future__ import annotations

import functools
import threading
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..design import (
    METHODS,
    DesignQuality,
    FlightDesign,
    LiveDesign,
    LiveModels,
    Suggestion,
    accuracy_law,
    cross_strip_images,
    design_auxiliary,
    design_block,
    design_from_block,
    suggest_control,
)
from .quality import STOPS
from .shapes import ramp
from .studio_live import PendingDesign, deferred, images_added, images_removed
from .studio_text import summary_markdown

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
#: the law's note for a design without a plan (a block from a file)
LAW_NONE = "no accuracy law: the block comes from a file, not from a regular flight plan"


def point_values(q: DesignQuality, block, key: str) -> F64:
    """The measure ``key`` per point in the unit of :data:`MEASURES` (NaN: none)."""
    label, unit, f, _ = MEASURES[key]
    if key == "sigma_xy":
        return q.sigma_xy * f
    if key == "sigma_z":
        return q.point_sigma[:, 2] * f
    if key == "redundancy":
        if not np.isfinite(q.redundancy).any():  # a method without image rays
            return np.full(block.n_points, np.nan)
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


def legend_html(scale: Scale, defined: bool = True) -> str:
    """A colour bar with the measure's name and the values at its ends (HTML); with
    ``defined`` False, the note that the method has no such measure (points grey)."""
    label, unit, _, worse_high = MEASURES[scale.key]
    if not defined:
        return (
            f'<div style="font-size:0.8em"><b>{label}</b>: not defined for the chosen method '
            "(points grey)</div>"
        )
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


def _locked(method):
    """Run a :class:`Studio` method under the studio's lock (GUI callbacks may run in
    several threads; the live design's lazy update must not run twice at once)."""

    @functools.wraps(method)
    def run(self, *args, **kwargs):
        with self.lock:
            return method(self, *args, **kwargs)

    return run


class Studio:
    """The studio's state: the plan, the live design, the method, the measure, the
    suggestion, the changes and their undo.

    No GUI here: :class:`~orientviz.viewer.studio_panel.StudioView` draws it and its panel
    edits it; the tests and the lessons drive it directly.

    Parameters
    ----------
    design : FlightDesign
        The plan (ignored when ``block`` is given).
    block, spec : Block and dict, optional
        A design block and its geometry (``base_m``) instead of a plan, e.g. from
        :func:`orientviz.design.design_from_block`; then there is no plan to change and no
        accuracy law.
    title : str, optional
        What the block is (a file name), for the summary.
    """

    def __init__(
        self, design: FlightDesign = START, *, block=None, spec=None, title: str | None = None
    ) -> None:  # fmt: skip
        self.lock = threading.RLock()
        self.measure = "sigma_z"
        self.method = "bundle"
        self.suggestion: Suggestion | None = None
        self.title = title
        #: every change in words, in order (control, plan, images, strips, method)
        self.log: list[str] = []
        #: per change that can be undone: ("control",) or ("structure", the state before)
        self._undo: list[tuple] = []
        #: independent models: the live models design of the block
        self._models: LiveModels | None = None
        if block is not None:
            self.design = None
            self._set_block(block.copy(), dict(spec))
        else:
            self._set_plan(design)

    @classmethod
    def from_file(cls, target: str, *, sigma_control: float = 0.02) -> Studio:
        """The studio on the geometry of a block problem file (or a shipped data set):
        solved as ``orientviz solve`` does, then made a design
        (:func:`orientviz.design.design_from_block`: projections as error-free image
        coordinates, fixed control weighted with ``sigma_control`` m)."""
        from ..io.solve import adjusted_problem, load_named, solve_problem  # files: on demand

        problem = load_named(target)
        block = adjusted_problem(problem, solve_problem(problem)).data
        b, spec = design_from_block(block, sigma_control=sigma_control)
        return cls(block=b, spec=spec, title=str(target))

    # ------------------------------------------------------------------ state
    @property
    def live(self) -> LiveDesign:
        """The bundle's live design of the block (structural changes made under the
        models method are applied now: :mod:`orientviz.viewer.studio_live`)."""
        if isinstance(self._live, PendingDesign):
            made = self._live.block
            self._live = self._live.apply()
            if self._models is not None and self._models.block is made:
                self._models.block = self._live.block  # the same block, made twice
        return self._live

    @live.setter
    def live(self, live: LiveDesign | PendingDesign) -> None:
        self._live = live

    def _now(self) -> LiveDesign | PendingDesign:
        """The live design a structural change starts from: as it is under the models
        method (its update waits until the bundle is shown), else applied."""
        return deferred(self._live) if self.method == "models" else self.live

    def _state(self) -> tuple:
        return (self.design, self._live, self.spec, self.law, self._models)

    def _restore(self, state: tuple) -> None:
        self.design, self._live, self.spec, self.law, self._models = state

    def _set_plan(self, design: FlightDesign) -> None:
        self.design = design
        block, self.spec = design_block(design)
        aux = design_auxiliary(block, design)
        self.live = LiveDesign(block, self.spec, auxiliary=aux)
        self.law = accuracy_law(design, self.spec)
        self._models = None

    def _set_block(self, block, spec) -> None:
        self.spec = spec
        aux = design_auxiliary(block, self.design) if self.design is not None else []
        self.live = LiveDesign(block, spec, auxiliary=aux)
        if self.design is None:
            self.law = {"sigma_xy": float("nan"), "sigma_z": float("nan"), "note": LAW_NONE}
        else:  # images added or removed: the law still describes the regular plan
            self.law = self._law_of_plan(accuracy_law(self.design, spec))
        self._models = None

    def _structural(self, label: str, change) -> DesignQuality:
        """Apply a change of the structure (a new design), keeping the old one for undo; a
        change the chosen method cannot take (e.g. independent models whose models cannot
        be formed any more) raises and leaves the old design."""
        before = self._state()
        try:
            change()
            q = self.quality
        except Exception:
            self._restore(before)
            raise
        self._undo.append(("structure", before))
        self.log.append(label)
        self.suggestion = None
        return q

    @_locked
    def set_plan(self, design: FlightDesign) -> DesignQuality:
        """Build the design of a (new) plan: strips, overlaps, σ … (undo restores the old)."""
        return self._structural(
            f"plan: {design.strips} × {design.images_per_strip}, p {design.forward_overlap:.0%}"
            f", q {design.side_overlap:.0%}, control {design.control}",
            lambda: self._set_plan(design),
        )

    def _set_live(self, live: LiveDesign | PendingDesign) -> None:
        """The design after a structural change updated by the live design (or, under
        the models method, to be updated when the bundle's quality is asked for)."""
        self.live = live
        if self.design is not None:  # the law still describes the regular plan
            self.law = self._law_of_plan(self.law)
        self._models = None

    @staticmethod
    def _law_of_plan(law: dict) -> dict:
        """The plan's accuracy law after images were added or removed: the same values
        (the law describes the regular plan; computed once per plan), said so."""
        note = "; for the plan without the images added or removed since"
        out = dict(law)
        if not out["note"].endswith(note):
            out["note"] += note
        return out

    def _aux_of(self):
        """The plan's auxiliary data of a changed block (their rows follow the images)."""
        design = self.design
        return None if design is None else (lambda block: design_auxiliary(block, design))

    def _images_added(self, label: str, X0, angles, strip, ids=None) -> DesignQuality:
        """Add images by the live design's update (auxiliary rows of the new images too)."""
        new = images_added(self._now(), X0, angles, strip=strip, ids=ids, auxiliary=self._aux_of())
        return self._structural(label, lambda: self._set_live(new))

    @_locked
    def add_cross_strip(self, x: float) -> DesignQuality:
        """Fly a cross strip along +Y at X = ``x`` (m) over the block."""
        X0, ang, strip, ids = cross_strip_images(self.block, self.spec, x)
        label = f"cross strip at X = {x:,.0f} m ({len(ids)} images)"
        return self._images_added(label, X0, ang, strip, ids)

    @_locked
    def remove_images(self, images, what: str | None = None) -> DesignQuality:
        """Remove images (indices) and their rays from the design."""
        idx = np.atleast_1d(np.asarray(images, np.int64))
        names = [self.block.images.ids[i] for i in idx]
        label = what or ("image " + ", ".join(names) + " removed")
        new = images_removed(self._now(), idx, label, auxiliary=self._aux_of())
        return self._structural(label, lambda: self._set_live(new))

    @_locked
    def add_image(self, xy) -> DesignQuality:
        """Add an image above the ground position ``xy`` (m) at the height, attitude and in
        the strip of the nearest projection centre."""
        I = self.block.images
        xy = np.asarray(xy, float)[:2]
        i = int(np.argmin(np.linalg.norm(I.X0[:, :2] - xy[None, :], axis=1)))
        X0 = np.r_[xy, I.X0[i, 2]]
        name = f"x{self.block.n_images:03d}"
        return self._images_added(
            f"image {name} added at X {xy[0]:,.0f} m, Y {xy[1]:,.0f} m (strip {I.strip[i]})",
            X0[None],
            I.angles[i][None],
            int(I.strip[i]),
        )

    @_locked
    def move_image(self, image: int, xy) -> DesignQuality:
        """Move image ``image`` to above the ground position ``xy`` (m), keeping its
        height, attitude, strip and id (the image removed, then added at the new place:
        two updates, one change to undo)."""
        I = self.block.images
        xy = np.asarray(xy, float)[:2]
        name, strip = I.ids[image], int(I.strip[image])
        X0 = np.r_[xy, I.X0[image, 2]][None]
        ang = I.angles[image][None].copy()
        label = f"image {name} moved to X {xy[0]:,.0f} m, Y {xy[1]:,.0f} m"
        aux = self._aux_of()
        new = images_removed(self._now(), [image], label, auxiliary=aux)
        new = images_added(new, X0, ang, strip=strip, ids=[name], auxiliary=aux)
        return self._structural(label, lambda: self._set_live(new))

    @_locked
    def remove_strip(self, strip: int) -> DesignQuality:
        """Remove every image of strip ``strip``."""
        idx = np.flatnonzero(self.block.images.strip == strip)
        return self.remove_images(idx, f"strip {strip} removed ({idx.size} images)")

    @_locked
    def set_method(self, method: str) -> DesignQuality:
        """Assess the design for ``"bundle"``, ``"models"`` or ``"polynomial"``
        (:data:`orientviz.design.METHODS`; the polynomial method has no design precision:
        the bundle's quality stays shown and :meth:`method_note` says so)."""
        if method not in METHODS:
            raise ValueError(f"method: expected one of {', '.join(METHODS)}, got {method!r}")
        if method != self.method:
            old, self.method = self.method, method
            try:
                self.quality  # noqa: B018  (computed now: a failure keeps the old method)
            except Exception:
                self.method = old
                raise
            self.log.append(f"method: {METHODS[method][0]}")
        return self.quality

    def method_note(self) -> str | None:
        """Why the chosen method shows no precision of its own (None if it does)."""
        return METHODS[self.method][1]

    # ------------------------------------------------------------------ control
    @_locked
    def set_control(self, point: int, sigma: float | None) -> DesignQuality:
        """Make ``point`` XYZ control with σ ``sigma`` m (None: make it a tie point)."""
        if sigma is None:
            self.live.remove_control(point)
        else:
            self.live.add_control(point, sigma)
        self._undo.append(("control",))
        self.log.append(self.live.history[-1])
        self.suggestion = None
        return self.quality

    @_locked
    def undo(self) -> DesignQuality:
        """Take the last change back (control, plan, images, strips)."""
        if not self._undo:
            raise ValueError("nothing to undo")
        kind = self._undo.pop()
        if kind[0] == "control":
            self.live.undo()
            self.log.append(self.live.history[-1])
        else:
            self._restore(kind[1])
            self.log.append(
                "undo: " + next(t for t in reversed(self.log) if not t.startswith("undo"))
            )
        self.suggestion = None
        return self.quality

    @property
    def block(self):
        """The current design block."""
        return self._live.block

    @property
    @_locked
    def quality(self) -> DesignQuality:
        """The current quality for the chosen method (the bundle's for the polynomial)."""
        if self.method != "models":
            return self.live.quality()
        # one factorisation per structure (block), control changes by updates
        if self._models is None or self._models.block is not self.block:
            self._models = LiveModels(self.block, self.spec, auxiliary=self._live.auxiliary)
        return self._models.sync()

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

    @_locked
    def suggest(self, sigma: float) -> Suggestion:
        """Suggest the next control point (σ ``sigma`` m) for the shown measure: worst
        σ_XY, worst σ_Z (also for redundancy and MDB) or largest δ̄0."""
        crit = {"sigma_xy": "sigma_xy", "external": "external"}.get(self.measure, "sigma_z")
        self.suggestion = suggest_control(self.live, criterion=crit, sigma=sigma)
        return self.suggestion

    @_locked
    def values(self) -> F64:
        """The chosen measure per point."""
        return point_values(self.quality, self.block, self.measure)

    @_locked
    def summary_markdown(self) -> str:
        """The block's figures next to the accuracy law's values, the weak spots
        (:func:`orientviz.viewer.studio_text.summary_markdown`)."""
        return summary_markdown(
            self.quality, self.block, self.design, self.law, self.method, self.title
        )

    def changes_markdown(self) -> str:
        """The list of changes (control, plan, images, strips, method) in order."""
        items = self.log
        if not items:
            return "*no changes yet*"
        return "\n".join(f"{k + 1}. {t}" for k, t in enumerate(items[-12:]))
