"""The legend of a block scene: one line per kind of element that is drawn now, and only those.

:func:`block_legend` reads what the scene holds (points by role, strips, ellipsoids,
the distortion field, the scale bar) and returns Markdown for the panel, with each
colour written as a coloured square (HTML) and named. No viser here.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..block import CHECK, CONTROL, TIE
from .block_geometry import COLORS, SCORE_RED


def swatch(rgb: Any, shape: str = "■") -> str:
    """A coloured character in HTML (``shape`` in the colour ``rgb``, 0-255)."""
    r, g, b = (int(v) for v in rgb)
    return f'<span style="color: rgb({r},{g},{b})">{shape}</span>'


def block_legend(scene: Any) -> str:
    """Markdown lines naming the colours of what ``scene`` (a BlockScene) draws."""
    st = scene.geo.state
    b = st.block
    kind = st.scores()[1] if b.n_observations else "|v|/σ"

    def shown(key: str) -> bool:
        return key in scene.nodes and bool(scene.nodes[key].visible)

    lines = [f"{swatch(COLORS['frustum'], '△')} images, {swatch(COLORS['selected'], '△')} "
             f"the selected image and its rays"]  # fmt: skip
    if shown("rays/selected") and getattr(scene, "selected", None) is not None:
        step, n_sel = scene.geo.selected_ray_step(scene.selected)
        if step > 1:
            lines[0] += f" (one in {step} of its {n_sel:,}: level of detail)"
    role = b.points.role
    pts = []

    for r, name, shape in ((TIE, "tie", "●"), (CONTROL, "control", "◆"), (CHECK, "check", "◆")):
        if np.any(role == r) and shown(f"points/{name}"):
            pts.append(f"{swatch(COLORS[name], shape)} {name}")
    if pts:
        lines.append(" ".join(pts) + " points")
    if shown("residuals"):
        lines.append(
            f"residual vectors {swatch((40, 160, 80))} 0 {swatch((240, 170, 20))} "
            f"{SCORE_RED / 2:g} {swatch((210, 30, 30))} {kind} ≥ {SCORE_RED:g}; {swatch(COLORS['scale_bar'], '▬')} "
            + getattr(scene, "scale_bar_text", "scale bar")
        )
    drawn, n = scene.geo.residuals_drawn
    if shown("residuals") and drawn < n:
        lines.append(f"(level of detail: the {drawn:,} largest of {n:,} residual vectors drawn)")
    if shown("rays/all"):
        step = scene.geo.ray_step
        every = f" (one in {step} of {n:,}: level of detail)" if step > 1 else ""
        lines.append(f"{swatch(COLORS['ray'], '▬')} all rays{every}")
    if shown("strips"):
        lines.append(f"{swatch(COLORS['strip'], '▬')} strips (projection centres in order)")
    if "ellipsoids" in scene.nodes and scene.ellipsoids_visible:
        lines.append(
            f"{swatch(COLORS['ellipsoid'], '●')} point ellipsoids "
            f"({scene.ellipsoid_options['level']:.0%}, ×{getattr(scene, 'ellipsoid_scale', 1):.3g})"
        )
    if "station_ellipsoids" in scene.nodes and scene.ellipsoids_visible:
        lines.append(
            f"{swatch(COLORS['station'], '●')} projection-centre ellipsoids "
            f"(×{getattr(scene, 'station_gain', 1):.3g})"
        )
    if scene.selected_point is not None:
        lines.append(f"{swatch(COLORS['selected'], '●')} the chosen point and its rays")
    extra = getattr(scene, "legend_extra", None)
    if extra:
        lines += list(extra)
    shown_extra = getattr(scene, "legend_deformation", None)  # a deformation view, while shown
    if shown_extra:
        lines.append(shown_extra)
    return "  \n".join(lines)
