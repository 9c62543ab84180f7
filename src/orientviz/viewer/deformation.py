"""Model deformation: how far the estimated block is from a reference, exaggerated and animated.

The reference is a second state of the same points — the truth of a simulation, or
the result before self-calibration or before a transformation. The scene shows

* ``/block/deformation/vectors`` — reference → estimate for every point, × k;
* ``/block/deformation/points`` — the points morphed to reference + t·k·(estimate −
  reference); the *morph* slider (t ∈ [0, 1]) and *play* animate between the two.

k is chosen so that the median displacement is drawn as half a point spacing
(shown in the panel). Units: m.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..model import Block
from . import geometry as g
from .block_geometry import COLORS
from .state import BlockState

F64 = NDArray[np.float64]


def deformation_vectors(estimate: F64, reference: F64) -> F64:
    """Displacements estimate − reference (p, 3) in m; NaN rows where either is missing."""
    return np.asarray(estimate, dtype=float) - np.asarray(reference, dtype=float)


def auto_scale(displacement: F64, spacing: float) -> float:
    """Exaggeration drawing the median |displacement| as half of ``spacing`` (1 if none)."""
    d = np.linalg.norm(displacement, axis=1)
    d = d[np.isfinite(d)]
    med = float(np.median(d)) if d.size else 0.0
    return 0.5 * spacing / med if med > 0 else 1.0


def morph(reference: F64, displacement: F64, t: float, k: float) -> F64:
    """Points at reference + t·k·displacement (p, 3) m, t ∈ [0, 1]."""
    return np.asarray(reference, dtype=float) + (t * k) * np.asarray(displacement, dtype=float)


def deformation_extra(state: BlockState, reference: Block):
    """An ``extra`` builder (see :class:`~orientviz.viewer.demos.Demo`) for the deformation view."""
    ref = reference.points.xyz.copy()

    def build(app: Any) -> dict:
        scene = app.scene
        frame, spacing = scene.geo.frame, scene.geo.spacing
        gui, sc = app.server.gui, app.server.scene
        ctl: dict[str, Any] = {}

        def current() -> tuple[F64, float]:
            d = deformation_vectors(state.block.points.xyz, ref)
            return d, auto_scale(d, spacing)

        d, k = current()
        R = frame.to_scene(ref)
        vec = sc.add_line_segments(
            "/block/deformation/vectors", g.vector_segments(R, d, k).astype(np.float32),
            COLORS["deformation"], thickness=2.0, thickness_units="screen", visible=False,
        )  # fmt: skip
        pts = sc.add_point_cloud(
            "/block/deformation/points", R.astype(np.float32), COLORS["deformation"],
            point_size=scene.geo.point_size, point_shape="circle", precision="float32", visible=False,
        )  # fmt: skip
        with gui.add_folder("Deformation", expand_by_default=False):
            ctl["show"] = gui.add_checkbox("show deformation", False)
            ctl["t"] = gui.add_slider("morph reference → estimate", 0.0, 1.0, 0.01, 1.0)
            ctl["play"] = gui.add_button("play")
            ctl["info"] = gui.add_markdown("")

        def redraw() -> None:
            d, k = current()
            t = float(ctl["t"].value)
            vec.points = g.vector_segments(R, d, k).astype(np.float32)
            pts.points = frame.to_scene(morph(ref, d, t, k)).astype(np.float32)
            rms = np.sqrt(np.nanmean(np.sum(d**2, axis=1)))
            ctl[
                "info"
            ].content = (
                f"estimate − reference: RMS {rms:.3g} m, drawn ×{k:.3g}; points at t = {t:.2f}"
            )

        def show(_e: Any = None) -> None:
            on = bool(ctl["show"].value)
            vec.visible = pts.visible = on
            scene.set_visible("points", not on)
            scene.set_visible("residuals", not on)

        def play(_e: Any = None) -> None:
            def run() -> None:
                for t in np.concatenate([np.linspace(0, 1, 40), np.linspace(1, 0, 40), [1.0]]):
                    ctl["t"].value = round(float(t), 2)
                    time.sleep(0.04)

            if not ctl["show"].value:
                ctl["show"].value = True
            threading.Thread(target=run, daemon=True).start()

        ctl["show"].on_update(app.guard(show))
        ctl["t"].on_update(app.guard(lambda _e: redraw()))
        ctl["play"].on_click(app.guard(play))
        scene.listeners.append(redraw)
        redraw()
        return {"deformation": ctl, "deformation_nodes": (vec, pts)}

    return build
