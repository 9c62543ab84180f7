"""The panel's "Act on the adjustment" folder: switch, drag, weight, undo, rewind.

Every action changes :attr:`BlockState.edits <orientviz.viewer.state.BlockState.edits>`
and re-solves warm-started from the current estimates
(:meth:`~orientviz.viewer.state.BlockState.act`). The answer is drawn in two passes: the
adjustment without its precision first (geometry, residuals, σ̂0 — the quick answer),
then the cofactors (normalised residuals, quality colours, ellipsoids; by default only
for blocks up to :data:`AUTO_PRECISION_IMAGES` images). Each action is
an entry of the "changes" list with its σ̂0; choosing an entry rewinds to it exactly,
"undo" goes one entry back.

Observations are chosen among the selected image's rays; control points from a list,
and "drag" puts viser's transform controls on the chosen control point (the
adjustment re-solves when the drag ends).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from . import solved

NONE = "—"
#: Above this many images (or :data:`~orientviz.viewer.solved.PRECISION_LIMIT` image
#: observations) the precision pass after an action or an adjustment is off by default
#: (large blocks: the quick answer stays quick; tick "precision after each action" to add
#: it, or ask for it once in the "Precision" folder).
AUTO_PRECISION_IMAGES: int = 500


class ActControls:
    """GUI of the actions, bound to a :class:`~orientviz.viewer.panel.BlockPanel`."""

    def __init__(self, panel: Any) -> None:
        self.panel = panel
        self.state = panel.state
        self.handles: dict[str, Any] = {}
        self.rays: list[int] = []
        b = self.state.block
        self.controls = [int(k) for k in np.flatnonzero(b.points.role == 1)]
        self.drag = None
        #: seconds of the last action: quick answer (solve + redraw) and with the precision
        self.last_timing: dict[str, float] = {}

    def build(self) -> ActControls:
        gui, h, p = self.panel.server.gui, self.handles, self.panel
        b = self.state.block
        with gui.add_folder("Act on the adjustment"):
            h["ray"] = gui.add_dropdown("ray of image", (NONE,), hint="the selected image's rays")
            h["toggle_ray"] = gui.add_button("ray off / on")
            h["weight"] = gui.add_number("weight ×", 1.0, min=1e-4, max=1e4, step=0.1)
            h["set_weight"] = gui.add_button("set weight of the ray")
            h["toggle_image"] = gui.add_button("selected image off / on")
            ids = tuple(b.points.ids[k] for k in self.controls) or (NONE,)
            h["control"] = gui.add_dropdown("control point", ids)
            h["toggle_control"] = gui.add_button("control off / on")
            h["drag"] = gui.add_checkbox("drag the control point", False)
            h["auto_precision"] = gui.add_checkbox(
                "precision after each action",
                b.n_images <= AUTO_PRECISION_IMAGES and b.n_observations <= solved.PRECISION_LIMIT,
                hint="cofactors, quality colours and ellipsoids after the quick answer",
            )  # fmt: skip
            h["undo"] = gui.add_button("undo")
            h["changes"] = gui.add_dropdown("changes (σ̂0)", (NONE,), hint="choose one to rewind")
            h["act_info"] = gui.add_markdown("")
        h["toggle_ray"].on_click(p.guard(lambda _e: self.toggle_ray()))
        h["set_weight"].on_click(p.guard(lambda _e: self.set_weight(float(h["weight"].value))))
        h["toggle_image"].on_click(p.guard(lambda _e: self.toggle_image()))
        h["toggle_control"].on_click(p.guard(lambda _e: self.toggle_control()))
        h["drag"].on_update(p.guard(lambda _e: self.show_drag(bool(h["drag"].value))))
        h["control"].on_update(p.guard(lambda _e: self.show_drag(bool(h["drag"].value))))
        h["auto_precision"].on_update(p.guard(lambda _e: self._precision_switched()))
        h["undo"].on_click(p.guard(lambda _e: self.undo()))
        h["changes"].on_update(p.guard(lambda _e: self.rewind_to_choice()))
        for name in ("toggle_control", "drag", "control"):
            h[name].disabled = not self.controls
        self.refresh()
        return self

    # ------------------------------------------------------------------ choices
    def chosen_ray(self) -> int:
        label = str(self.handles["ray"].value)
        if label == NONE or not self.rays:
            raise ValueError("choose a ray of the selected image first")
        return self.rays[int(label.split(".")[0]) - 1]

    def chosen_control(self) -> int:
        if not self.controls:
            raise ValueError("the block has no control points")
        ids = self.state.block.points.ids
        return self.controls[
            [ids[k] for k in self.controls].index(str(self.handles["control"].value))
        ]

    # ------------------------------------------------------------------ actions
    def _do(self, action: Any) -> None:
        """Run ``action`` (a state method re-solving without the precision), then redraw."""
        p, st = self.panel, self.state
        self.last_timing = {}
        t = time.perf_counter()
        action(precision=False)
        p.scene.update()
        p.refresh(quality=False)
        self.last_timing["answer"] = time.perf_counter() - t
        if self.handles["auto_precision"].value:
            try:
                self.add_precision()
            except Exception:  # e.g. a defect only the precision finds: the change is undone
                st.undo()
                del st.changes[st.change_cursor + 1 :]
                self._after_rewind()
                raise
            self.last_timing["with precision"] = time.perf_counter() - t
            st.update_current_change()
        else:
            p.refresh()
        self.refresh()

    def _precision_switched(self) -> None:
        """The precision switched on again: add it to the current state now."""
        if self.handles["auto_precision"].value and self.state.at_result:
            self.add_precision()
            self.state.update_current_change()
            self.refresh()

    def add_precision(self) -> None:
        """Second pass: the cofactors at the new solution, then colours and ellipsoids."""
        p, st = self.panel, self.state
        res = st.result
        if res is None or res.normalized_residuals is not None:
            return
        st.step(20, precision=True)
        p.scene.update()
        p.scene.update_ellipsoids()
        p.refresh()

    def toggle_ray(self) -> None:
        j = self.chosen_ray()
        self._do(lambda **kw: self.state.toggle_observation(j, **kw))

    def set_weight(self, factor: float) -> None:
        j = self.chosen_ray()
        self._do(lambda **kw: self.state.set_weight(j, factor, **kw))

    def toggle_image(self) -> None:
        i = self.panel.scene.selected
        self._do(lambda **kw: self.state.toggle_image(i, **kw))

    def toggle_control(self) -> None:
        k = self.chosen_control()
        self._do(lambda **kw: self.state.toggle_control(k, **kw))

    def move_control(self, k: int, xyz: np.ndarray) -> None:
        """Give control point ``k`` the object coordinates ``xyz`` (m) and re-solve."""
        self._do(lambda **kw: self.state.move_control(k, xyz, **kw))

    def undo(self) -> None:
        self.state.undo()
        self._after_rewind()

    def rewind(self, k: int) -> None:
        self.state.rewind(k)
        self._after_rewind()

    def rewind_to_choice(self) -> None:
        label = str(self.handles["changes"].value)
        if label == NONE:
            return
        k = int(label.split(".")[0])
        if k != self.state.change_cursor:
            self.rewind(k)

    def _after_rewind(self) -> None:
        p = self.panel
        if self.drag is not None:  # the gizmo goes back with the control point
            self.show_drag(True)
        p.scene.update()
        p.set_exaggeration()
        p.scene.update_ellipsoids()
        p.select(p.scene.selected)
        p.refresh()

    # ------------------------------------------------------------------ drag
    def show_drag(self, on: bool) -> None:
        """Show (or remove) the transform controls on the chosen control point."""
        sc = self.panel.scene
        if self.drag is not None:
            self.drag.remove()
            self.drag = None
        if not on or not self.controls:
            return
        k = self.chosen_control()
        known = self.state.edits.known[k]
        xyz = np.where(np.isfinite(known), known, self.state.block.points.xyz[k])
        self.drag = sc.scene.add_transform_controls(
            f"{sc.root}/control_drag", scale=3.0 * sc.geo.spacing, disable_rotations=True,
            position=tuple(float(v) for v in sc.geo.frame.to_scene(xyz)),
        )  # fmt: skip
        self.drag_point = k
        self.drag.on_update(self.panel.guard(self._dragged))

    def _dragged(self, event: Any) -> None:
        if getattr(event, "phase", "end") == "end":  # re-solve once, at the release
            self.drop()

    def drop(self) -> None:
        """The drag ended: the control point takes the controls' position."""
        sc = self.panel.scene
        xyz = np.asarray(self.drag.position, dtype=float) + sc.geo.frame.origin
        self.move_control(self.drag_point, xyz)

    # ------------------------------------------------------------------ read-outs
    def refresh(self) -> None:
        """Rays of the selected image, the list of changes, what is switched off."""
        st, h, p = self.state, self.handles, self.panel
        b, e = st.block, st.edits
        i = p.scene.selected
        self.rays = [int(j) for j in np.flatnonzero(b.observations.image == i)]
        scores = getattr(p.scene, "last_scores", None)
        rows = []
        for k, j in enumerate(self.rays):
            sc = "" if scores is None or not np.isfinite(scores[j]) else f" {scores[j]:.2f}"
            off = "" if e.obs_on[j] else " (off)"
            w = "" if e.weight[j] == 1 else f" ×{e.weight[j]:g}"
            rows.append(f"{k + 1}. {b.points.ids[b.observations.point[j]]}{sc}{off}{w}")
        changes = tuple(f"{k}. {c.label} — σ̂0 = {c.sigma0:.4g}" for k, c in enumerate(st.changes))
        p._syncing = True
        try:
            keep = str(h["ray"].value)
            h["ray"].options = tuple(rows) or (NONE,)
            same = [r for r in rows if r.split(" ")[0] == keep.split(" ")[0]]
            h["ray"].value = same[0] if same else (rows[0] if rows else NONE)
            h["changes"].options = changes
            h["changes"].value = changes[st.change_cursor]
        finally:
            p._syncing = False
        n_off = int(np.count_nonzero(~e.obs_on))
        lines = [
            f"switched off: {_count(n_off, 'ray')}, {_count(np.count_nonzero(~e.image_on), 'image')}, "
            f"{_count(np.count_nonzero(~e.control_on), 'control point')}",
        ]
        mp = st.mapping
        if mp is not None and (mp.dropped_images.size or mp.dropped_points.size):
            lines.append(
                f"left out for lack of rays: {_count(mp.dropped_images.size, 'image')}, "
                f"{_count(mp.dropped_points.size, 'point')}"
            )
        t = self.last_timing
        if "answer" in t:
            more = f", with precision {1000 * t['with precision']:.0f} ms" if len(t) > 1 else ""
            lines.append(f"last action: answer {1000 * t['answer']:.0f} ms{more}")
        h["act_info"].content = "  \n".join(lines)


def _count(n: int | np.integer, noun: str) -> str:
    """``n`` and ``noun``, plural unless ``n`` is 1 ("1 image", "0 rays")."""
    return f"{int(n)} {noun}" + ("" if int(n) == 1 else "s")
