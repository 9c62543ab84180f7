"""The panel's "Precision" folder: confidence ellipsoids and the correlation strip.

The ellipsoids of the object points (all, or only the selected image's) and of the
projection centres (the selected image and its neighbours) are drawn at the chosen
confidence level (χ² quantile, 3 degrees of freedom), exaggerated so that they can be
seen (the factor is shown). The selected image's correlations with its neighbours —
the images that share a point with it — are a heat strip: one 6 × 6 tile of abs(ρ)
per neighbour, rows the selected image's X0 Y0 Z0 ω φ κ, columns the neighbour's.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from . import solved
from .panel_act import AUTO_PRECISION_IMAGES
from .precision_view import (
    STRIP_NEIGHBOURS,
    confidence_factor,
    heat_strip,
    neighbour_correlations,
)

#: dropdown label → confidence level
LEVELS: dict[str, float] = {"68.3 %": 0.683, "90 %": 0.90, "95 %": 0.95, "99 %": 0.99}
POINT_MODES: tuple[str, ...] = ("all", "selected image", "none")


class PrecisionControls:
    """GUI of the ellipsoids and correlations, bound to a :class:`~orientviz.viewer.panel.BlockPanel`."""

    def __init__(self, panel: Any) -> None:
        self.panel = panel
        self.handles: dict[str, Any] = {}
        self.neighbours: np.ndarray = np.zeros(0, np.int64)
        self.rho: np.ndarray = np.zeros((0, 6, 6))

    def build(self) -> PrecisionControls:
        gui, h, p = self.panel.server.gui, self.handles, self.panel
        opt = p.scene.ellipsoid_options
        with gui.add_folder("Precision"):
            h["level"] = gui.add_dropdown("confidence", tuple(LEVELS), initial_value="95 %")
            h["points"] = gui.add_dropdown(
                "point ellipsoids", POINT_MODES, initial_value=opt["points"]
            )
            h["stations"] = gui.add_checkbox("station ellipsoids", bool(opt["stations"]))
            h["gain"] = gui.add_slider(
                "ellipsoid × (log10, 0 = auto)", -3.0, 3.0, 0.1, 0.0,
                hint="0 draws the median ellipsoid about a third of a point spacing",
            )  # fmt: skip
            h["info"] = gui.add_markdown("")
            h["compute"] = gui.add_button(
                "compute the precision",
                hint="cofactors at the solution: normalised residuals, quality, ellipsoids",
            )
            h["strip"] = gui.add_image(np.full((42, 42, 3), 255, np.uint8), label="correlations")
            h["strip_text"] = gui.add_markdown("")
        for name in ("level", "points", "stations", "gain"):
            h[name].on_update(p.guard(lambda _e: self.apply()))
        h["compute"].on_click(p.guard(lambda _e: self.compute()))
        self.refresh()
        return self

    def apply(self) -> None:
        """Take the controls' values and redraw the ellipsoids."""
        h, sc = self.handles, self.panel.scene
        opt = sc.ellipsoid_options
        opt["level"] = LEVELS[str(h["level"].value)]
        opt["points"] = str(h["points"].value)
        opt["stations"] = bool(h["stations"].value)
        opt["factor"] = 10 ** float(h["gain"].value)
        sc.update_ellipsoids(new_gain=True)
        self.refresh()

    def compute(self) -> None:
        """The precision pass on request (large blocks open without it)."""
        act = self.panel.act
        act.add_precision()
        self.panel.state.update_current_change()
        act.refresh()
        self.refresh()

    def refresh(self) -> None:
        """The read-out of the ellipsoids and the correlation strip of the selected image."""
        p, h = self.panel, self.handles
        sc, st = p.scene, p.state
        opt = sc.ellipsoid_options
        res = st.result if st.at_result else None
        b = st.block
        missing = res is not None and res.normalized_residuals is None
        h["compute"].visible = missing
        if res is None:
            h["info"].content = "*no adjustment at this state: no ellipsoids*"
        elif missing:
            n = b.n_observations
            big = n > solved.PRECISION_LIMIT or b.n_images > AUTO_PRECISION_IMAGES
            why = (
                f"{n:,} image points, above the viewer's limit of {solved.PRECISION_LIMIT:,} for "
                "the precision at every solve"
                if big
                else "switched off after each action"
            )
            h["info"].content = (
                f"**precision not computed** ({why}): no normalised residuals (the "
                "residuals are scored |v|/σ), quality measures or ellipsoids until you press "
                "*compute the precision*"
            )
        else:
            k = confidence_factor(opt["level"])
            n_pts = (
                int(np.asarray(sc.nodes["ellipsoids"].vertices).shape[0] // 42)
                if ("ellipsoids" in sc.nodes)
                else 0
            )
            h["info"].content = (
                f"{100 * opt['level']:.3g} % ellipsoids: k = {k:.2f} (χ², 3 dof) × σ, "
                f"drawn ×{getattr(sc, 'ellipsoid_scale', 1.0):.3g}; {n_pts} points"
                + (", stations of the selected image and its neighbours" if opt["stations"] else "")
            )
        i = sc.selected
        self.neighbours, self.rho = neighbour_correlations(res, i, b.n_images)
        nb, rho = self.neighbours[:STRIP_NEIGHBOURS], self.rho[:STRIP_NEIGHBOURS]
        h["strip"].visible = nb.size > 0
        if nb.size:
            h["strip"].image = heat_strip(rho)
            rows = ", ".join(
                f"{b.images.ids[j]} ({np.nanmax(np.abs(r)):.2f})" for j, r in zip(nb, rho)
            )
            h["strip_text"].content = (
                f"abs(ρ) of **{b.images.ids[i]}** (rows X0 Y0 Z0 ω φ κ) with its neighbours "
                f"(columns), white 0 … dark red 1, left to right: {rows}"
            )
        else:
            h["strip_text"].content = "*correlations: after an adjustment with its precision*"
