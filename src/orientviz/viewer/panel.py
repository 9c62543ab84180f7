"""The GUI panel of a block: orientation sliders, adjustment buttons, scrubber, residual list.

Angles on the panel are in gon (slider steps of 1 c = 0.01 gon), or in degrees for a
problem file in degrees; positions in m, or in model units for a reconstruction whose
scale is arbitrary (:class:`~orientviz.viewer.view_units.ViewUnits`).
Rotations follow the block's sequence (ω-φ-κ by default, R = R_ω R_φ R_κ). Every
callback runs through :meth:`BlockPanel.guard` (the viewer's
:class:`~orientviz.viewer.callbacks.CallbackGate`), which turns an exception into a message
in the panel and on the terminal instead of stopping the server.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ..units import from_rad, to_rad
from .callbacks import CallbackGate
from .legend import block_legend
from .panel_act import ActControls
from .panel_camera import CameraControls
from .panel_precision import PrecisionControls
from .panel_quality import QualityControls
from .scene import BlockScene
from .sliders import Sliders
from .snapshot import panel_text, view_png

ANGLES = ("omega", "phi", "kappa")
POSITIONS = ("X0", "Y0", "Z0")
RAY_MODES = ("none", "selected image", "all")


def position_span(height: float, arbitrary_scale: bool = False) -> tuple[float, float]:
    """Range ± span and step of the position sliders: 3 % of the cameras' distance to
    the points rounded to a power of ten. In metres at least 1 m (1, 10, 100 m) in steps
    of 0.1 m; in a reconstruction's model units (an arbitrary scale) no floor, in steps
    of a hundredth of the span."""
    h = 0.03 * height if height > 0 else 1.0
    if arbitrary_scale:
        span = float(10 ** np.round(np.log10(h)))
        return span, span / 100
    return float(10 ** np.round(np.log10(max(h, 1.0)))), 0.1


class BlockPanel:
    """GUI controls bound to a :class:`BlockScene`.

    Parameters
    ----------
    server : viser.ViserServer
        The server (for ``gui``, clients and notifications).
    scene : BlockScene
        The scene the controls act on (and its state).
    report : callable
        ``report(message)``: shows an error message (panel, notification, terminal).
    gate : CallbackGate, optional
        The viewer's gate for GUI callbacks (one for the whole viewer); a new one with
        ``report`` if not given.
    """

    def __init__(
        self,
        server: Any,
        scene: BlockScene,
        report: Callable[[str], None],
        gate: CallbackGate | None = None,
    ) -> None:
        self.server = server
        self.scene = scene
        self.state = scene.geo.state
        self.report = report
        self.gate = gate if gate is not None else CallbackGate(report)
        self.handles: dict[str, Any] = {}
        self._syncing = False
        #: wall-clock seconds of the last slider-driven redraw (state change to nodes sent)
        self.last_redraw_s = float("nan")

    # ------------------------------------------------------------------ helpers
    def guard(self, fn: Callable[..., Any]) -> Callable[..., Any]:
        """Wrap a callback through the viewer's gate: exceptions become a reported message,
        calls run one at a time and not at all after :meth:`close`; a call while the panel
        sets its own sliders (an echo) is ignored."""
        return self.gate.wrap(fn, skip=lambda: self._syncing)

    def close(self) -> None:
        """Wait for a callback still running, then ignore every later one (the server stops)."""
        self.gate.close()

    # ------------------------------------------------------------------ building
    def build(self) -> BlockPanel:
        gui, b, h = self.server.gui, self.state.block, self.handles
        geo, u = self.scene.geo, self.state.units
        #: where a flight puts the camera from its target, per unit of distance
        self._back = np.array([-0.3, -1.0, 0.9]) if geo.aerial else -1.38 * geo.view
        with gui.add_folder("Legend"):
            h["legend"] = gui.add_markdown("")
        sliders = self.sliders = Sliders(gui, h)  # the server sets these too
        with gui.add_folder("Image orientation") as folder:
            m = b.n_images
            sliders.add("image", folder, "image #", 0, max(m - 1, 1), 1, 0, disabled=m < 2)
            h["image_id"] = gui.add_markdown("")
            span, step = position_span(geo.height, u.arbitrary_scale)
            for name in POSITIONS:
                sliders.add(
                    name, folder, f"{name} [{u.length_name}]", -span, span, step, 0.0,
                    hint="position of the projection centre",
                )  # fmt: skip
            for name in ANGLES:
                sliders.add(
                    name, folder, f"{name} [{u.angle}]", -2.0, 2.0, 0.01, 0.0,
                    hint=f"slider step 0.01 {u.angle}" + (" = 1 c" if u.angle == "gon" else ""),
                )  # fmt: skip
        with gui.add_folder("Adjustment") as folder:
            h["step"] = gui.add_button("one iteration")
            h["run"] = gui.add_button("run to convergence")
            h["reset"] = gui.add_button("reset")
            sliders.add("iteration", folder, "iteration", 0, 1, 1, 0, disabled=True)
            h["stats"] = gui.add_markdown("")
        with gui.add_folder("Largest residuals"):
            h["largest"] = gui.add_dropdown("observation", ("—",))
            h["fly"] = gui.add_button("fly to")
        with gui.add_folder("Display"):
            self.auto_k = self.scene.exaggeration
            h["exaggeration"] = gui.add_slider(
                "residual × (log10)", -3.0, 3.0, 0.05, 0.0,
                hint="× 10^value of the fixed scale (see the scale bar in the scene)",
            )  # fmt: skip
            h["rescale"] = gui.add_button(
                "fit the residual scale to this state",
                hint="the scale stays fixed while you iterate; this chooses it anew",
            )
            h["save_png"] = gui.add_button(
                "save the view as PNG (with legend)",
                hint="the picture as you see it, the legend and σ̂0 beside it (a download)",
            )
            h["rays"] = gui.add_dropdown("rays", RAY_MODES, initial_value="selected image")
            flown = bool(np.any(b.images.strip >= 0))  # strips and models: a flown block's
            for key, on in (
                ("frustums", True), ("points", True), ("residuals", True),
                ("strips", True), ("models", False), ("ellipsoids", True),
            ):  # fmt: skip
                shown = flown or key not in ("strips", "models")
                h[f"show_{key}"] = gui.add_checkbox(key, on, visible=shown)

        self.quality = QualityControls(self).build()
        self.precision = PrecisionControls(self).build()
        self.act = ActControls(self).build()
        self.camera = CameraControls(self).build()
        self._bind()
        self.scene.on_image_click = self.guard(self._select_from_click)
        self.select(0)
        self.refresh()
        return self

    def _bind(self) -> None:
        h = self.handles
        sliders = self.sliders
        sliders.on_update("image", self.guard(lambda _e: self.select(int(h["image"].value))))
        for name in POSITIONS + ANGLES:
            sliders.on_update(name, self.guard(lambda _e: self.apply_sliders()))
        h["step"].on_click(self.guard(lambda _e: self.adjust(1)))
        h["run"].on_click(self.guard(lambda _e: self.adjust(50)))
        h["reset"].on_click(self.guard(lambda _e: self.reset()))
        sliders.on_update(
            "iteration", self.guard(lambda _e: self.replay(int(h["iteration"].value)))
        )
        h["fly"].on_click(self.guard(lambda _e: self.fly_to_selected()))
        h["largest"].on_update(self.guard(lambda _e: self.fly_to_selected()))
        h["exaggeration"].on_update(self.guard(lambda _e: self.set_exaggeration()))
        h["rescale"].on_click(self.guard(lambda _e: self.set_exaggeration(auto=True)))
        h["save_png"].on_click(self.guard(lambda e: self.save_png(e.client)))
        h["rays"].on_update(self.guard(lambda _e: self._show_rays(str(h["rays"].value))))
        for key in ("frustums", "points", "residuals", "strips", "models", "ellipsoids"):
            h[f"show_{key}"].on_update(
                self.guard(lambda _e, k=key: self._show(k, bool(self.handles[f"show_{k}"].value)))
            )

    # ------------------------------------------------------------------ actions
    def _select_from_click(self, k: int) -> None:
        self.sliders.set("image", k)  # triggers select()

    def select(self, k: int) -> None:
        """Select image ``k``: centre the sliders on its orientation, show its rays."""
        b = self.state.block
        self.scene.select(k)
        self._base = (b.images.X0[k].copy(), b.images.angles[k].copy())
        self._syncing = True
        try:
            for name in POSITIONS + ANGLES:
                self.sliders.set(name, 0.0)
        finally:
            self._syncing = False
        u = self.state.units
        ang = from_rad(b.images.angles[k], u.angle)
        X0 = b.images.X0[k]
        h = self.scene.geo.height  # decimals: 1 in m, ~3 significant in model units
        d = max(1, 2 - int(np.floor(np.log10(h)))) if u.arbitrary_scale and h > 0 else 1
        if getattr(self, "act", None) is not None:
            self.act.refresh()
            self.precision.refresh()
        if getattr(self, "camera", None) is not None:
            self.camera.refresh()
        self.handles["image_id"].content = (
            f"**{self.state.image_label(k)}** — sliders are changes of "
            f"X0 = ({X0[0]:.{d}f}, {X0[1]:.{d}f}, {X0[2]:.{d}f}) {u.length_name}, "
            f"ω φ κ = ({ang[0]:.4f}, {ang[1]:.4f}, {ang[2]:.4f}) {u.angle}"
        )
        if "legend" in self.handles:  # the selected image's rays: how many are drawn
            self.update_legend()

    def apply_sliders(self) -> None:
        """Set the selected image's orientation from the sliders and redraw at once."""
        t = time.perf_counter()
        k = self.scene.selected
        X0, ang = self._base
        dX = np.array([float(self.handles[n].value) for n in POSITIONS])
        dA = to_rad(
            np.array([float(self.handles[n].value) for n in ANGLES]), self.state.units.angle
        )
        self.state.set_exterior(k, X0 + dX, ang + dA)
        self.scene.update([k])
        self.refresh(full=False)
        self.last_redraw_s = time.perf_counter() - t

    def adjust(self, max_iter: int) -> None:
        """One iteration (``max_iter=1``) or a run to convergence from the current state."""
        # large blocks: the precision only on request (the "Precision" folder)
        res = self.state.step(max_iter, precision=bool(self.act.handles["auto_precision"].value))
        self.state.record(
            "one iteration" if max_iter == 1 else f"adjusted ({res.iterations} iterations)"
        )
        self.scene.update()
        self.set_exaggeration()  # the scale stays: the vectors shrink as the block converges
        self.scene.update_ellipsoids()
        self.select(self.scene.selected)
        self.refresh()
        if not res.converged and max_iter > 1:
            self.report(f"the adjustment did not converge: {res.reason}")

    def show_pending(self, job: Any) -> None:
        """The line on the solve running in the background (``job``; None: remove it)."""
        with self.gate.lock:
            self._pending_line = None if job is None else job.status()
            self.refresh(full=False)

    def take_result(self, result: Any) -> None:
        """Show the solve that ran in the background (the state adopts it); the residual
        scale stays, so the vectors shrink from the start values to the solution."""
        with self.gate.lock:
            self.state.adopt(result)
            self._pending_line = None
            self.scene.update()
            self.set_exaggeration()
            self.scene.update_ellipsoids()
            self.select(self.scene.selected)
            self.refresh()

    def reset(self) -> None:
        self.state.reset()
        self.scene.update()
        self.set_exaggeration()
        self.scene.update_ellipsoids()
        self.select(self.scene.selected)
        self.refresh()

    def replay(self, k: int) -> None:
        """Show history record ``k`` (the iteration scrubber)."""
        self.state.replay(k)
        self.scene.update()
        self.set_exaggeration()
        self.scene.update_ellipsoids(new_gain=False)
        self.select(self.scene.selected)
        self.refresh(full=False)

    def set_exaggeration(self, auto: bool = False) -> None:
        """Exaggeration = base value × 10^slider.

        The base value is chosen once, from the state first shown (the median residual
        a third of a point spacing), and kept while the student iterates, replays or acts,
        so that convergence shows as vectors shrinking; ``auto`` (the button "fit the
        residual scale to this state") chooses it anew from the current state.
        """
        if auto:
            self.auto_k = self.scene.geo.auto_exaggeration()
        self.scene.set_exaggeration(self.auto_k * 10 ** float(self.handles["exaggeration"].value))
        self.refresh(full=False)
        self.update_legend()

    # ------------------------------------------------------------------ read-outs
    def refresh(self, full: bool = True, quality: bool = True) -> None:
        """Update σ0, the list of largest residuals, (``full``) the scrubber range and
        (``quality``) the quality colours and the list of changes."""
        st, h = self.state, self.handles
        e = st.misclosure()
        scores, kind = st.scores(e)
        n_hist = len(st.history)
        if full:
            self._syncing = True
            try:
                h["iteration"].max = max(n_hist - 1, 1)
                self.sliders.set("iteration", st.cursor)
                h["iteration"].disabled = n_hist < 2
            finally:
                self._syncing = False
        res = st.result
        lines = [
            f"σ0 of the current state: **{st.sigma0(e):.10g}** (redundancy {st.redundancy()})",
            f"state: {st.history[st.cursor].label} of {n_hist - 1}"
            + (" (moved by hand)" if st.moved else ""),
            f"max {kind}: {np.nanmax(scores, initial=0.0):.2f} · residual exaggeration ×{self.scene.exaggeration:.3g}",
        ]
        pending = getattr(self, "_pending_line", None)
        if pending:
            lines.append(pending)
        elif res is not None:
            lines.append(
                f"last adjustment: σ̂0 = {res.sigma0:.10g}, {res.iterations} it., {res.reason}"
            )
            if res.normalized_residuals is None:
                lines.append("precision not computed: see the *Precision* folder")
        h["stats"].content = "  \n".join(lines)
        # the list of largest residuals follows every change
        top = st.largest(10, scores)
        self._top = [int(j) for j in top]
        labels = tuple(
            f"{i + 1}. {st.observation_label(j)}  {kind} = {scores[j]:.2f}"
            for i, j in enumerate(self._top)
        ) or ("—",)
        self._syncing = True
        try:
            h["largest"].options = labels
            h["largest"].value = labels[0]
        finally:
            self._syncing = False
        if full and quality and getattr(self, "quality", None) is not None:
            self.quality.recolour()
            self.precision.refresh()
            self.act.refresh()
            if getattr(self, "camera", None) is not None:
                self.camera.refresh()
            self.update_legend()

    def _show_rays(self, mode: str) -> None:
        self.scene.set_rays(mode)
        self.update_legend()

    def _show(self, key: str, visible: bool) -> None:
        self.scene.set_visible(key, visible)
        self.update_legend()

    def update_legend(self) -> None:
        """Name the colours of what the scene draws now (:func:`~orientviz.viewer.legend.block_legend`)."""
        self.handles["legend"].content = block_legend(self.scene)

    def save_png(self, client: Any, size: tuple[int, int] = (800, 1000)) -> bytes:
        """Send ``client`` a PNG of its view (height, width px) with the legend and σ̂0 beside it."""
        render = client.get_render(height=size[0], width=size[1], transport_format="png")
        title = getattr(self, "title", "") or "orientviz"
        png = view_png(render, panel_text(self), title)
        client.send_file_download("orientviz-view.png", png, save_immediately=True)
        self.last_png = png
        return png

    def fly_to_selected(self) -> None:
        """Move every client's camera to the observation chosen in the residual list."""
        label = str(self.handles["largest"].value)
        if not getattr(self, "_top", None) or label == "—":
            return
        j = self._top[int(label.split(".")[0]) - 1]
        self.fly_to_observation(j)

    def fly_to_observation(self, j: int) -> None:
        """Select the observation's image and fly the camera to its point."""
        b = self.state.block
        img = int(b.observations.image[j])
        self.sliders.set("image", img)
        self.scene.select_point(int(b.observations.point[j]))  # a marker on its point
        self.fly_to(self.scene.geo.frame.to_scene(b.points.xyz[b.observations.point[j]]))

    def fly_to_image(self, i: int) -> None:
        """Select image ``i`` and fly the camera to its projection centre's footprint."""
        b = self.state.block
        self.sliders.set("image", int(i))
        geo = self.scene.geo
        axis = -b.rotations()[i][:, 2]  # the camera's viewing direction (aerial: down)
        target = geo.frame.to_scene(b.images.X0[i]) + 0.5 * geo.height * axis
        self.fly_to(target, 1.5 * geo.height)

    def fly_to_point(self, k: int) -> None:
        """Select point ``k`` (marked, with its rays) and fly the camera to it."""
        b = self.state.block
        self.scene.select_point(int(k))
        seen = np.flatnonzero(b.observations.point == k)
        if seen.size:  # its first image becomes the selected image
            self.sliders.set("image", int(b.observations.image[seen[0]]))
        self.fly_to(self.scene.geo.frame.to_scene(b.points.xyz[k]))

    def fly_to(self, target: np.ndarray, distance: float | None = None) -> None:
        """Move every client's camera smoothly to look at ``target`` (scene frame, m)."""
        d = 8.0 * self.scene.geo.spacing if distance is None else float(distance)
        target = np.asarray(target, dtype=float)
        for client in self.server.get_clients().values():
            start_pos = np.asarray(client.camera.position, dtype=float)
            start_look = np.asarray(client.camera.look_at, dtype=float)
            end_pos = target + self._back * d
            for t in np.linspace(0.0, 1.0, 12)[1:]:
                s = t * t * (3 - 2 * t)
                with client.atomic():
                    client.camera.look_at = start_look + s * (target - start_look)
                    client.camera.position = start_pos + s * (end_pos - start_pos)
                time.sleep(0.02)
        self.fly_target = target
