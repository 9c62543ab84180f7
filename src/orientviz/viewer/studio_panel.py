"""The design studio's scene and panel: measure and legend, summary and law, control, plan, undo.

:class:`StudioView` draws a :class:`~orientviz.viewer.studio.Studio` (nodes under
``/design``) and builds the :class:`StudioPanel`.

Folders:

* **Design quality** — *colour by* (σ_XY, σ_Z, redundancy, MDB, δ̄0), the legend, the
  block's summary next to Ebner's accuracy laws, the weak spots;
* **Control** — a point (its id; or *click places control* and a click on the ground),
  its σ, *make control* / *make tie*; *suggest control point* and *accept suggestion*;
  *undo*; the list of changes;
* **Plan** — strips, images per strip, overlaps, image σ, control σ, GNSS and *apply plan*
  (builds the design again).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from . import geometry as g
from .studio import (
    CONTROL_COLOUR,
    MEASURES,
    STATION_COLOUR,
    STRIP_COLOUR,
    SUGGESTED_COLOUR,
    Studio,
    legend_html,
    scale_of,
)

LABELS = {key: v[0] for key, v in MEASURES.items()}


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
            h["measure"] = gui.add_dropdown(
                "colour by", tuple(LABELS.values()), initial_value=LABELS[self.studio.measure]
            )
            h["legend"] = gui.add_html("")
            h["summary"] = gui.add_markdown("")
        with gui.add_folder("Control"):
            h["point"] = gui.add_text("point", initial_value="")
            h["sigma"] = gui.add_number("control σ [cm]", 2.0, min=0.1, max=100.0, step=0.1)
            h["make_control"] = gui.add_button("make control")
            h["make_tie"] = gui.add_button("make tie")
            h["click"] = gui.add_checkbox("click places control", False)
            h["suggest"] = gui.add_button("suggest control point")
            h["suggestion"] = gui.add_markdown("")
            h["accept"] = gui.add_button("accept suggestion", disabled=True)
            h["undo"] = gui.add_button("undo")
            h["changes"] = gui.add_markdown("")
        with gui.add_folder("Plan", expand_by_default=False):
            h["strips"] = gui.add_slider("strips", 1, 30, 1, d.strips)
            h["images"] = gui.add_slider("images per strip", 3, 60, 1, d.images_per_strip)
            h["p"] = gui.add_slider(
                "forward overlap [%]", 55, 85, 1, round(100 * d.forward_overlap)
            )
            h["q"] = gui.add_slider("side overlap [%]", 5, 60, 1, round(100 * d.side_overlap))
            h["sigma_image"] = gui.add_number("image σ [µm]", d.sigma_image_mm * 1e3, min=0.5)
            h["layout"] = gui.add_dropdown(
                "control layout", ("corners", "perimeter", "chains", "full", "none"),
                initial_value=d.control,
            )  # fmt: skip
            h["spacing"] = gui.add_slider("control spacing [bases]", 1, 20, 1, d.control_spacing)
            h["gnss"] = gui.add_number("GNSS σ [m] (0 = none)", d.sigma_gnss or 0.0, min=0.0)
            h["apply"] = gui.add_button("apply plan")
        guard = self.view.app.guard
        h["measure"].on_update(guard(lambda _e: self.set_measure()))
        h["make_control"].on_click(guard(lambda _e: self.make_control()))
        h["make_tie"].on_click(guard(lambda _e: self.make_tie()))
        h["suggest"].on_click(guard(lambda _e: self.suggest()))
        h["accept"].on_click(guard(lambda _e: self.accept()))
        h["undo"].on_click(guard(lambda _e: self.undo()))
        h["apply"].on_click(guard(lambda _e: self.apply_plan()))
        h["click"].on_update(guard(lambda _e: self.click_mode()))
        return self

    # ------------------------------------------------------------------ actions
    def set_measure(self) -> None:
        label = self.h["measure"].value
        self.studio.measure = next(k for k, v in LABELS.items() if v == label)
        self.view.redraw()

    def _sigma(self) -> float:
        return float(self.h["sigma"].value) / 100.0

    def make_control(self, point: int | None = None) -> None:
        st = self.studio
        j = st.point_index(self.h["point"].value.strip()) if point is None else point
        st.live.add_control(j, self._sigma())
        st.suggestion = None
        self.view.redraw()

    def make_tie(self) -> None:
        st = self.studio
        st.live.remove_control(st.point_index(self.h["point"].value.strip()))
        st.suggestion = None
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
        self.studio.live.undo()
        self.studio.suggestion = None
        self.view.redraw()

    def apply_plan(self) -> None:
        h, st = self.h, self.studio
        gnss = float(h["gnss"].value)
        new = st.design.with_(
            strips=int(h["strips"].value), images_per_strip=int(h["images"].value),
            forward_overlap=float(h["p"].value) / 100.0, side_overlap=float(h["q"].value) / 100.0,
            sigma_image_mm=float(h["sigma_image"].value) / 1e3, control=str(h["layout"].value),
            control_spacing=int(h["spacing"].value), chain_spacing=int(h["spacing"].value),
            sigma_control=self._sigma(), sigma_gnss=gnss if gnss > 0 else None,
        )  # fmt: skip
        st.set_plan(new)
        st.plan_history.append(
            f"plan: {new.strips} × {new.images_per_strip}, p {new.forward_overlap:.0%}, "
            f"q {new.side_overlap:.0%}, control {new.control}"
        )
        self.view.redraw(reframe=True)

    def click_mode(self) -> None:
        sc = self.view.app.server.scene
        if self.h["click"].value:
            sc.on_pointer_event(event_type="click")(self.view.app.guard(self._clicked))
        else:
            sc.remove_pointer_callback()

    def _clicked(self, event: Any) -> None:
        o = np.asarray(event.ray_origin, float)
        d = np.asarray(event.ray_direction, float)
        if o is None or d is None or abs(d[2]) < 1e-9:
            return
        z = float(np.mean(self.view.frame.to_scene(self.studio.block.points.xyz)[:, 2]))
        t = (z - o[2]) / d[2]
        if t <= 0:
            return
        hit = o + t * d + self.view.frame.origin
        j = self.studio.nearest_point(hit[:2])
        self.h["point"].value = self.studio.block.points.ids[j]
        self.make_control(j)

    # ------------------------------------------------------------------ display
    def refresh(self) -> None:
        """Legend, summary, suggestion and changes after the current design."""
        st, h = self.studio, self.h
        h["legend"].content = legend_html(self.view.scale)
        h["summary"].content = st.summary_markdown()
        sug = st.suggestion
        h["suggestion"].content = sug.describe() if sug is not None else ""
        h["accept"].disabled = sug is None
        h["changes"].content = st.changes_markdown()


class StudioView:
    """The studio's scene (nodes under ``/design``) and its panel."""

    def __init__(self, app: Any, studio: Studio | None = None) -> None:
        self.app = app
        self.studio = studio or Studio()
        self.nodes: dict[str, Any] = {}
        self.panel = None

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
        seg = g.polyline_segments(X0, b.images.strip)
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
        if self.panel is not None:
            self.panel.refresh()
