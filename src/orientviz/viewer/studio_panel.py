"""The design studio's scene and panel: measure and legend, summary and law, control, plan, undo.

:class:`StudioView` draws a :class:`~orientviz.viewer.studio.Studio` (nodes under
``/design``) and builds the :class:`StudioPanel`.

Folders:

* **Design quality** — the *method* (bundle, independent models, polynomial: the last has
  no design precision, said in the summary), *colour by* (σ_XY, σ_Z, redundancy, MDB,
  δ̄0), the 95 % ellipsoids (exaggerated), the legend, the block's summary next to Ebner's
  accuracy laws, the weak spots;
* **Control and images** — what *a click on the ground* does (make the nearest point
  control or tie, add an image there, fly a cross strip through the place, remove the
  nearest image or strip, put the image gizmo on the nearest image), a *control gizmo* to
  drag (its release makes the nearest point control), an *image gizmo* to drag (its
  release moves the image there), a point by id and its σ, *make control* / *make tie*; *suggest control point* and *accept
  suggestion*; *undo* (every kind of change); the list of changes;
* **Plan** — strips, images per strip, overlaps, image scale (flying height), image σ,
  control layout and σ, GNSS σ (absolute), statoscope and APR σ (offsets per strip) and
  *apply plan*
  (builds the design again).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..design import METHODS
from . import geometry as g
from .shapes import icosphere
from .studio import (
    CONTROL_COLOUR,
    MEASURES,
    START,
    STATION_COLOUR,
    STRIP_COLOUR,
    SUGGESTED_COLOUR,
    Studio,
    legend_html,
    scale_of,
)
from .studio_memory import keep_large_arrays_on_heap

LABELS = {key: v[0] for key, v in MEASURES.items()}
METHOD_LABELS = {key: v[0] for key, v in METHODS.items()}
#: what a click on the ground does
CLICKS = {
    "nothing": "does nothing",
    "control": "makes the nearest point control",
    "tie": "makes the nearest point a tie point",
    "add": "adds an image there (the nearest strip's height and heading)",
    "cross": "flies a cross strip through it",
    "image": "removes the nearest image",
    "strip": "removes the nearest strip",
    "pick": "puts the image gizmo on the nearest image",
}
ELLIPSOID_COLOUR = (60, 140, 220)


class StudioPanel:
    """GUI handles of the studio (``h``) and their callbacks."""

    def __init__(self, view: Any) -> None:
        self.view = view
        self.h: dict[str, Any] = {}

    @property
    def studio(self):
        return self.view.studio

    def build(self) -> StudioPanel:
        gui = self.view.app.server.gui
        h = self.h
        d = self.studio.design
        with gui.add_folder("Design quality"):
            h["method"] = gui.add_dropdown(
                "method", tuple(METHOD_LABELS.values()),
                initial_value=METHOD_LABELS[self.studio.method],
            )  # fmt: skip
            h["measure"] = gui.add_dropdown(
                "colour by", tuple(LABELS.values()), initial_value=LABELS[self.studio.measure]
            )
            h["ellipsoids"] = gui.add_checkbox("95 % ellipsoids", False)
            h["exaggeration"] = gui.add_slider("ellipsoid exaggeration", 1, 500, 1, 50)
            h["legend"] = gui.add_html("")
            h["summary"] = gui.add_markdown("")
        with gui.add_folder("Control and images"):
            h["click"] = gui.add_dropdown(
                "a click on the ground", tuple(CLICKS.values()), initial_value=CLICKS["nothing"]
            )
            h["gizmo"] = gui.add_checkbox("control gizmo (drag, release)", False)
            h["image_gizmo"] = gui.add_checkbox("image gizmo (drag an image, release)", False)
            h["point"] = gui.add_text("point", initial_value="")
            h["sigma"] = gui.add_number("control σ [cm]", 2.0, min=0.1, max=100.0, step=0.1)
            h["make_control"] = gui.add_button("make control")
            h["make_tie"] = gui.add_button("make tie")
            h["suggest"] = gui.add_button("suggest control point")
            h["suggestion"] = gui.add_markdown("")
            h["accept"] = gui.add_button("accept suggestion", disabled=True)
            h["undo"] = gui.add_button("undo")
            h["changes"] = gui.add_markdown("")
        plan = self.studio.design is not None
        with gui.add_folder("Plan", expand_by_default=False, visible=plan):
            d = d or START
            h["strips"] = gui.add_slider("strips", 1, 30, 1, d.strips)
            h["images"] = gui.add_slider("images per strip", 3, 60, 1, d.images_per_strip)
            h["p"] = gui.add_slider(
                "forward overlap [%]", 55, 85, 1, round(100 * d.forward_overlap)
            )
            h["q"] = gui.add_slider("side overlap [%]", 5, 60, 1, round(100 * d.side_overlap))
            h["scale"] = gui.add_number(
                "image scale 1 : m_B (H = c·m_B)", d.scale, min=1_000.0, max=200_000.0, step=500.0
            )
            h["sigma_image"] = gui.add_number("image σ [µm]", d.sigma_image_mm * 1e3, min=0.5)
            h["layout"] = gui.add_dropdown(
                "control layout", ("corners", "perimeter", "chains", "full", "none"),
                initial_value=d.control,
            )  # fmt: skip
            h["spacing"] = gui.add_slider("control spacing [bases]", 1, 20, 1, d.control_spacing)
            h["gnss"] = gui.add_number("GNSS σ [m] (0 = none)", d.sigma_gnss or 0.0, min=0.0)
            h["gnss_offsets"] = gui.add_checkbox("GNSS shift per strip", d.gnss_offsets)
            h["statoscope"] = gui.add_number(
                "statoscope σ [m] (0 = none)", d.sigma_statoscope or 0.0, min=0.0
            )
            h["apr"] = gui.add_number("APR σ [m] (0 = none)", d.sigma_apr or 0.0, min=0.0)
            h["apply"] = gui.add_button("apply plan")
        guard = self.view.app.guard
        h["method"].on_update(guard(lambda _e: self.set_method()))
        h["measure"].on_update(guard(lambda _e: self.set_measure()))
        h["ellipsoids"].on_update(guard(lambda _e: self.view.redraw()))
        h["exaggeration"].on_update(guard(lambda _e: self.view.redraw()))
        h["gizmo"].on_update(guard(lambda _e: self.view.gizmo(self.h["gizmo"].value)))
        h["image_gizmo"].on_update(
            guard(lambda _e: self.view.image_gizmo(self.h["image_gizmo"].value))
        )
        h["make_control"].on_click(guard(lambda _e: self.make_control()))
        h["make_tie"].on_click(guard(lambda _e: self.make_tie()))
        h["suggest"].on_click(guard(lambda _e: self.suggest()))
        h["accept"].on_click(guard(lambda _e: self.accept()))
        h["undo"].on_click(guard(lambda _e: self.undo()))
        h["apply"].on_click(guard(lambda _e: self.apply_plan()))
        h["click"].on_update(guard(lambda _e: self.click_mode()))
        self._clicking = False
        return self

    # ------------------------------------------------------------------ actions
    def set_measure(self) -> None:
        label = self.h["measure"].value
        self.studio.measure = next(k for k, v in LABELS.items() if v == label)
        self.view.redraw()

    def set_method(self) -> None:
        label = self.h["method"].value
        self.studio.set_method(next(k for k, v in METHOD_LABELS.items() if v == label))
        self.view.redraw()

    def _sigma(self) -> float:
        return float(self.h["sigma"].value) / 100.0

    def make_control(self, point: int | None = None) -> None:
        st = self.studio
        j = st.point_index(self.h["point"].value.strip()) if point is None else point
        st.set_control(j, self._sigma())
        self.view.redraw()

    def make_tie(self, point: int | None = None) -> None:
        st = self.studio
        j = st.point_index(self.h["point"].value.strip()) if point is None else point
        st.set_control(j, None)
        self.view.redraw()

    def suggest(self) -> None:
        self.studio.suggest(self._sigma())
        self.view.redraw()

    def accept(self) -> None:
        sug = self.studio.suggestion
        if sug is None:
            return
        self.h["point"].value = sug.point_id
        self.make_control(sug.point)

    def undo(self) -> None:
        self.studio.undo()
        self.view.redraw()

    def apply_plan(self) -> None:
        h, st = self.h, self.studio
        gnss = float(h["gnss"].value)
        new = (st.design or START).with_(
            strips=int(h["strips"].value), images_per_strip=int(h["images"].value),
            forward_overlap=float(h["p"].value) / 100.0, side_overlap=float(h["q"].value) / 100.0,
            scale=float(h["scale"].value),
            sigma_image_mm=float(h["sigma_image"].value) / 1e3, control=str(h["layout"].value),
            control_spacing=int(h["spacing"].value), chain_spacing=int(h["spacing"].value),
            sigma_control=self._sigma(), sigma_gnss=gnss if gnss > 0 else None,
            gnss_offsets=bool(h["gnss_offsets"].value),
            sigma_statoscope=float(h["statoscope"].value) or None,
            sigma_apr=float(h["apr"].value) or None,
        )  # fmt: skip
        st.set_plan(new)
        self.view.redraw(reframe=True)

    def click_mode(self) -> None:
        sc = self.view.app.server.scene
        on = self.h["click"].value != CLICKS["nothing"]
        if on and not self._clicking:
            self._click_cb = sc.on_click()(self.view.app.guard(self._clicked))
        elif not on and self._clicking:
            sc.remove_click_callback(self._click_cb)
        self._clicking = on

    def ground(self, event: Any) -> Any:
        """The object point (X, Y, Z) where a click's ray meets the mean ground (None: none)."""
        if event.ray_origin is None or event.ray_direction is None:
            return None
        o = np.asarray(event.ray_origin, float)
        d = np.asarray(event.ray_direction, float)
        if abs(d[2]) < 1e-9:
            return None
        z = float(np.mean(self.view.frame.to_scene(self.studio.block.points.xyz)[:, 2]))
        t = (z - o[2]) / d[2]
        return None if t <= 0 else o + t * d + self.view.frame.origin

    def _clicked(self, event: Any) -> None:
        hit = self.ground(event)
        if hit is None:
            return
        self.act_at(hit[:2], next(k for k, v in CLICKS.items() if v == self.h["click"].value))

    def act_at(self, xy: Any, what: str) -> None:
        """Do ``what`` (a key of :data:`CLICKS`) at the ground position ``xy`` (m)."""
        st = self.studio
        if what in ("control", "tie"):
            j = st.nearest_point(xy)
            self.h["point"].value = st.block.points.ids[j]
            st.set_control(j, self._sigma() if what == "control" else None)
        elif what == "cross":
            st.add_cross_strip(float(xy[0]))
        elif what == "add":
            st.add_image(xy)
        elif what in ("image", "strip", "pick"):
            X0 = st.block.images.X0[:, :2]
            i = int(np.argmin(np.linalg.norm(X0 - np.asarray(xy)[None, :2], axis=1)))
            if what == "image":
                st.remove_images([i])
            elif what == "strip":
                st.remove_strip(int(st.block.images.strip[i]))
            else:
                self.h["image_gizmo"].value = True
                self.view.image_gizmo(True, i)
                return
        else:
            return
        self.view.redraw()

    # ------------------------------------------------------------------ display
    def refresh(self) -> None:
        """Legend, summary, suggestion and changes after the current design."""
        st, h = self.studio, self.h
        h["legend"].content = legend_html(self.view.scale, self.view.defined)
        h["summary"].content = st.summary_markdown()
        sug = st.suggestion
        h["suggestion"].content = sug.describe() if sug is not None else ""
        h["accept"].disabled = sug is None
        h["changes"].content = st.changes_markdown()


class StudioView:
    """The studio's scene (nodes under ``/design``) and its panel."""

    def __init__(self, app: Any, studio: Studio | None = None) -> None:
        keep_large_arrays_on_heap()  # the designs' large temporaries (studio_memory)
        self.app = app
        self.studio = studio or Studio()
        self.nodes: dict[str, Any] = {}
        self.panel = None
        self.dragged: str | None = None  # id of the image under the image gizmo

    def build(self) -> dict:
        """Add the nodes and the panel; return the camera and the view (``"studio"``)."""
        self._frame()
        self.panel = StudioPanel(self).build()
        self.redraw()
        pos, look = g.framing(self.frame.to_scene(self.studio.block.points.xyz))
        return {"camera": (pos, look, self.frame.size), "studio": self}

    def _frame(self) -> None:
        b = self.studio.block
        self.frame = g.SceneFrame.around(np.vstack([b.points.xyz, b.images.X0]))
        self.scale = None

    def redraw(self, reframe: bool = False) -> None:
        """Draw points, control, stations and strips after the current design."""
        if reframe:
            self._frame()
        st = self.studio
        sc = self.app.server.scene
        b, f = st.block, self.frame
        P = f.to_scene(b.points.xyz).astype(np.float32)
        vals = st.values()
        self.scale = scale_of(vals, st.measure)
        self.defined = bool(np.isfinite(vals).any())
        cols = self.scale.colours(vals)
        size = f.size
        ctrl = st.quality.control
        self.colours = cols
        self.nodes["points"] = sc.add_point_cloud(
            "/design/points", P, cols, point_size=0.012 * size, point_shape="circle",
            precision="float32",
        )  # fmt: skip
        cp = P[ctrl] if ctrl.any() else np.full((1, 3), np.nan, np.float32)
        cp = cp + np.float32([0.0, 0.0, 0.004 * size])
        self.nodes["control"] = sc.add_point_cloud(
            "/design/control", cp, CONTROL_COLOUR, point_size=0.03 * size,
            point_shape="diamond", precision="float32",
        )  # fmt: skip
        X0 = f.to_scene(b.images.X0).astype(np.float32)
        self.nodes["stations"] = sc.add_point_cloud(
            "/design/stations", X0, STATION_COLOUR, point_size=0.01 * size, precision="float32"
        )
        along = _along_strip(b.images.X0, b.images.strip)  # an added/moved image in place
        seg = g.polyline_segments(X0[along], b.images.strip[along])
        if len(seg):
            self.nodes["strips"] = sc.add_line_segments(
                "/design/strips", np.asarray(seg, np.float32), STRIP_COLOUR, thickness=1.5,
                thickness_units="screen",
            )  # fmt: skip
        sug = st.suggestion
        if sug is not None:
            sp = P[[sug.point]] + np.float32([0.0, 0.0, 0.008 * size])
            self.nodes["suggested"] = sc.add_point_cloud(
                "/design/suggested", sp, SUGGESTED_COLOUR, point_size=0.045 * size,
                point_shape="sparkle", precision="float32",
            )  # fmt: skip
        elif "suggested" in self.nodes:
            self.nodes.pop("suggested").remove()
        self._ellipsoids(P)
        if self.panel is not None:
            self.panel.refresh()

    def _ellipsoids(self, P: Any) -> None:
        """The points' 95 % confidence ellipsoids, exaggerated (one mesh), if asked for."""
        h = self.panel.h if self.panel is not None else {}
        old = self.nodes.pop("ellipsoids", None)
        if old is not None:
            old.remove()
        if not (h.get("ellipsoids") is not None and h["ellipsoids"].value):
            return
        q = self.studio.quality
        k = float(h["exaggeration"].value)
        verts, faces = ellipsoid_mesh(P, q.ellipsoid_axes * k, q.ellipsoid_dirs)
        if len(faces):
            self.nodes["ellipsoids"] = self.app.server.scene.add_mesh_simple(
                "/design/ellipsoids", verts, faces, color=ELLIPSOID_COLOUR, opacity=0.45,
                flat_shading=False,
            )  # fmt: skip

    def gizmo(self, on: bool) -> None:
        """Show (or hide) the control gizmo: drag it and release, and the point nearest to
        it becomes control."""
        old = self.nodes.pop("gizmo", None)
        if old is not None:
            old.remove()
        if not on:
            return
        P = self.frame.to_scene(self.studio.block.points.xyz)
        self._planar_gizmo("gizmo", 0.08, P.mean(axis=0), self.gizmo_released)

    def image_gizmo(self, on: bool, image: int | None = None) -> None:
        """Show (or hide) the image gizmo on the projection centre of ``image`` (default:
        the image nearest to the block's centre): drag it and release, and the image moves
        there (:meth:`Studio.move_image <orientviz.viewer.studio.Studio.move_image>`)."""
        old = self.nodes.pop("image_gizmo", None)
        if old is not None:
            old.remove()
        if not on:
            return
        I = self.studio.block.images
        if image is None:
            c = I.X0[:, :2].mean(axis=0)
            image = int(np.argmin(np.linalg.norm(I.X0[:, :2] - c, axis=1)))
        self.dragged = I.ids[image]
        self._planar_gizmo("image_gizmo", 0.06, self.frame.to_scene(I.X0[image]),
                           self.image_released)  # fmt: skip

    def _planar_gizmo(
        self, name: str, size: float, position: Any, released: Callable[[Any], None]
    ) -> None:
        """Add a gizmo that moves in the scene's X, Y plane (no rotations) at ``position``,
        ``size`` × the scene's extent, calling ``released(position)`` when it is let go; kept
        in ``self.nodes[name]``."""
        lim = 2.0 * self.frame.size
        gz = self.app.server.scene.add_transform_controls(
            f"/design/{name}", scale=size * self.frame.size, disable_rotations=True,
            active_axes=(True, True, False), position=tuple(float(v) for v in position),
            translation_limits=((-lim, lim), (-lim, lim), (-lim, lim)),
        )  # fmt: skip

        def moved(event: Any) -> None:
            if getattr(event, "phase", "end") == "end":
                released(np.asarray(gz.position, float))

        gz.on_update(self.app.guard(moved))
        self.nodes[name] = gz

    def image_released(self, position: Any) -> None:
        """Move the image under the image gizmo to its position (scene frame, m): same
        height, attitude, strip and id."""
        ids = self.studio.block.images.ids
        if self.dragged not in ids:  # removed meanwhile: the gizmo picks the nearest one
            self.image_gizmo(True)
            return
        xy = (np.asarray(position, float) + self.frame.origin)[:2]
        self.studio.move_image(ids.index(self.dragged), xy)
        self.redraw()

    def gizmo_released(self, position: Any) -> None:
        """Make the point nearest to the gizmo's position (scene frame, m) control."""
        xy = (np.asarray(position, float) + self.frame.origin)[:2]
        self.panel.act_at(xy, "control")


def _along_strip(X0: Any, strip: Any) -> Any:
    """Image order for the flight lines: by strip, and within a strip along its longer
    horizontal extent (an image added or moved later sits in its place on the line)."""
    X0, strip = np.asarray(X0, float), np.asarray(strip)
    key = np.zeros(strip.size)
    for s in np.unique(strip):
        k = np.flatnonzero(strip == s)
        ax = int(np.argmax(np.ptp(X0[k, :2], axis=0)))
        key[k] = X0[k, ax]
    return np.lexsort((key, strip))


SPHERE = icosphere(1)  # 42 vertices, 80 triangles, radius 1


def ellipsoid_mesh(centres: Any, axes: Any, dirs: Any) -> tuple[Any, Any]:
    """One mesh of ellipsoids: semi-axes ``axes`` (p, 3) along the columns of ``dirs``
    (p, 3, 3) around ``centres`` (p, 3); points with non-finite axes are left out."""
    sv, sf = SPHERE
    ok = np.isfinite(axes).all(axis=1) & np.isfinite(dirs).all(axis=(1, 2))
    C, A, D = np.asarray(centres, float)[ok], axes[ok], dirs[ok]
    # vertex v of ellipsoid k: C_k + D_k diag(A_k) v
    V = C[:, None, :] + np.einsum("kij,kj,vj->kvi", D, A, sv)
    F = sf[None, :, :] + (sv.shape[0] * np.arange(C.shape[0]))[:, None, None]
    return V.reshape(-1, 3).astype(np.float32), F.reshape(-1, 3).astype(np.uint32)


DESCRIPTION = (
    "Plan a block before it is flown: the colours show the design's predicted quality (no "
    "measurements, the bundle's own normal equations). Make points control or tie, fly "
    "cross strips or remove images and strips by clicking the ground (*Control and "
    "images*), drag the control gizmo or an image (image gizmo), ask for the best next control point, switch the "
    "method, change strips, overlaps and σ under *Plan*; the summary compares with Ebner's "
    "accuracy laws."
)
