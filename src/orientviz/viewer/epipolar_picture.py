"""A small raster picture of the normalised (epipolar) images of a pair, for the panel.

:func:`normalised_picture` draws the output of
:func:`orientviz.viewer.pair_rays.normalised_pair` with Pillow into an RGB array that
the pair demo shows beside the scene (viser ``gui.add_image``). Left and right image side
by side, x to the right and y up (image mm); the row of the selected point — its
epipolar line — runs across both. In the right image each point is drawn where the left
partner's row would put it plus its y-parallax × an exaggeration, joined to that row by
a short bar: with the right dials every bar vanishes.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

BACKGROUND = (255, 255, 255)
FRAME = (150, 150, 150)
POINT = (70, 80, 100)
BAR = (0, 140, 170)
SELECTED = (200, 0, 130)
ROW = (250, 130, 0)


def picture_exaggeration(
    p_y: NDArray[np.float64], mm_per_px: float, target_px: float = 12.0
) -> float:
    """Factor that draws the 90th percentile of ``|p_y|`` (mm) as ``target_px`` pixels.

    Kept within [1, 10⁴]; 1 when the parallax would stay below a pixel even at 10⁴
    (an oriented pair: rounding noise is not blown up into bars).
    """
    p90 = float(np.percentile(np.abs(p_y), 90)) if len(p_y) else 0.0
    if p90 * 1e4 < mm_per_px:
        return 1.0
    return float(np.clip(target_px * mm_per_px / p90, 1.0, 1e4))


def normalised_picture(
    norm: dict[str, Any],
    selected: int | None = None,
    *,
    width: int = 320,
    exaggeration: float | None = None,
) -> tuple[NDArray[np.uint8], float]:
    """Draw the normalised pair.

    Parameters
    ----------
    norm : dict
        From :func:`~orientviz.viewer.pair_rays.normalised_pair` (``left``, ``right``,
        ``p_y``, ``half_format``).
    selected : int, optional
        Index of the point whose row (epipolar line) is drawn.
    width : int
        Picture width in pixels (height ≈ width / 2).
    exaggeration : float, optional
        Factor for the y-parallax bars (default :func:`picture_exaggeration`).

    Returns
    -------
    image : ndarray of uint8, shape (h, width, 3)
    exaggeration : float
        The factor used.
    """
    from PIL import Image, ImageDraw, ImageFont

    L, R, p = np.asarray(norm["left"]), np.asarray(norm["right"]), np.asarray(norm["p_y"])
    half = 1.15 * float(norm["half_format"])
    pad, top = 4, 18
    side = (width - 3 * pad) // 2
    height = side + top + pad
    mm_px = 2 * half / side
    k = picture_exaggeration(p, mm_px) if exaggeration is None else float(exaggeration)
    img = Image.new("RGB", (width, height), BACKGROUND)
    draw = ImageDraw.Draw(img)
    try:
        font = ImageFont.load_default(size=12)
    except (TypeError, OSError):  # a Pillow without FreeType
        font = ImageFont.load_default()

    def to_px(xy: NDArray[np.float64], panel: int) -> NDArray[np.float64]:
        x0 = pad + panel * (side + pad)
        u = x0 + (xy[:, 0] + half) / (2 * half) * side
        v = top + (half - xy[:, 1]) / (2 * half) * side
        return np.column_stack([u, v])

    hf = float(norm["half_format"])
    box = np.array([[-hf, -hf], [hf, hf]])
    for panel, title in ((0, "left"), (1, f"right, bars x{k:.3g}")):
        (u0, v1), (u1, v0) = to_px(box, panel)
        draw.rectangle([u0, v0, u1, v1], outline=FRAME)
        draw.text((pad + panel * (side + pad), 3), title, fill=(0, 0, 0), font=font)
    right_drawn = np.column_stack([R[:, 0], L[:, 1] - k * p])  # y1' − k (y1' − y2')
    base = to_px(np.column_stack([R[:, 0], L[:, 1]]), 1)
    a, b = to_px(L, 0), to_px(right_drawn, 1)
    if selected is not None:
        row = to_px(L[selected : selected + 1], 0)[0, 1]
        draw.line([pad, row, width - pad, row], fill=ROW, width=1)
    r = 2.5
    for i in range(len(L)):
        col = SELECTED if i == selected else POINT
        rr = 4.0 if i == selected else r
        draw.ellipse([a[i, 0] - rr, a[i, 1] - rr, a[i, 0] + rr, a[i, 1] + rr], fill=col)
        draw.line([base[i, 0], base[i, 1], b[i, 0], b[i, 1]], fill=BAR, width=2)
        draw.ellipse([b[i, 0] - rr, b[i, 1] - rr, b[i, 0] + rr, b[i, 1] + rr], fill=col)
    return np.asarray(img, dtype=np.uint8), k
