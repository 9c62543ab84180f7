"""The panel's "Colour by quality" folder: measure, legend, the worst images and points.

Frustums and points are coloured by the chosen measure of
:mod:`orientviz.viewer.quality` (computed from the current adjustment); the legend is
the colour scale as an image with the values at its ends. Choosing an entry of the
"worst images" or "worst points" list flies every client's camera there and selects
it (the image in the orientation panel, the point with its rays).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from .block_geometry import COLORS
from .quality import MEASURES, Quality, colour_bar, compute_quality, legend_text

#: dropdown label → measure key (None: colours by role, as without this folder)
CHOICES: dict[str, str | None] = {"role (no quality)": None} | {
    v[0]: k for k, v in MEASURES.items()
}
NONE = "—"
#: Frustum colour of an image switched off.
OFF_GREY = (175, 175, 175)


class QualityControls:
    """GUI of the quality colouring, bound to a :class:`~orientviz.viewer.panel.BlockPanel`."""

    def __init__(self, panel: Any) -> None:
        self.panel = panel
        self.handles: dict[str, Any] = {}
        self.quality: Quality | None = None
        self.worst_images: list[int] = []
        self.worst_points: list[int] = []

    def build(self) -> QualityControls:
        gui, h, p = self.panel.server.gui, self.handles, self.panel
        with gui.add_folder("Colour by quality"):
            h["measure"] = gui.add_dropdown(
                "colour by", tuple(CHOICES), initial_value="role (no quality)",
                hint="frustums and points coloured by a measure of the adjustment",
            )  # fmt: skip
            h["legend_bar"] = gui.add_image(np.zeros((14, 240, 3), np.uint8), label="scale")
            h["legend"] = gui.add_markdown("")
            h["worst_images"] = gui.add_dropdown("worst images", (NONE,))
            h["worst_points"] = gui.add_dropdown("worst points", (NONE,))
        h["measure"].on_update(p.guard(lambda _e: self.recolour()))
        h["worst_images"].on_update(p.guard(lambda _e: self.fly_to_worst("image")))
        h["worst_points"].on_update(p.guard(lambda _e: self.fly_to_worst("point")))
        self.recolour()
        return self

    @property
    def key(self) -> str | None:
        return CHOICES[str(self.handles["measure"].value)]

    def recolour(self) -> None:
        """Recompute the measure from the current adjustment; colour, legend and lists."""
        sc, st, h = self.panel.scene, self.panel.state, self.handles
        key = self.key
        visible = key is not None
        for name in ("legend_bar", "legend", "worst_images", "worst_points"):
            h[name].visible = visible
        if key is None:  # colours by role; images switched off grey
            self.quality = None
            off = ~st.edits.image_on
            rgb = None
            if off.any():
                rgb = np.tile(np.asarray(COLORS["frustum"], np.uint8), (off.size, 1))
                rgb[off] = OFF_GREY
            sc.colour_images(rgb)
            sc.colour_points(None)
            return
        q = compute_quality(st.block, st.result if st.at_result else None, key)
        self.quality = q
        rgb = q.colours(q.image)
        rgb[~st.edits.image_on] = OFF_GREY  # switched off (no measure: grey anyway)
        sc.colour_images(rgb)
        sc.colour_points(q.colours(q.point))
        h["legend_bar"].image = colour_bar(q)
        # a length measure in the file's length unit (a reconstruction: model units)
        text = legend_text(replace(q, unit=st.units.length_name) if q.unit == "m" else q)
        if not st.at_result:
            text += "  \n*(no adjustment at this state: run one to see the measure)*"
        h["legend"].content = text
        b = st.block
        self.worst_images = [int(i) for i in q.worst("image", 10)]
        self.worst_points = [int(i) for i in q.worst("point", 10)]
        self._set_options(
            "worst_images", [(b.images.ids[i], q.image[i]) for i in self.worst_images]
        )
        self._set_options(
            "worst_points", [(b.points.ids[i], q.point[i]) for i in self.worst_points]
        )

    def _set_options(self, name: str, rows: list[tuple[str, float]]) -> None:
        labels = (NONE,) + tuple(f"{k + 1}. {ident}  {v:.3g}" for k, (ident, v) in enumerate(rows))
        p = self.panel
        p._syncing = True
        try:
            self.handles[name].options = labels
            self.handles[name].value = NONE
        finally:
            p._syncing = False

    def fly_to_worst(self, which: str) -> None:
        """Fly to and select the entry chosen in the worst-images or worst-points list."""
        label = str(self.handles[f"worst_{which}s"].value)
        if label == NONE:
            return
        k = int(label.split(".")[0]) - 1
        if which == "image":
            self.panel.fly_to_image(self.worst_images[k])
        else:
            self.panel.fly_to_point(self.worst_points[k])
