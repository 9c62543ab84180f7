"""What a lecturer takes away from the viewer: the view with its legend as a PNG, and the
panel's numbers in the exported HTML page.

* :func:`view_png` puts the rendered view (the browser's picture of the scene,
  ``client.get_render``) beside the legend and the panel's read-out (σ̂0, state, largest
  residual) into one PNG: the legend's coloured symbols keep their colours.
* :func:`with_panel` adds the panel's text (title, σ̂0 and the adjustment's read-out,
  legend) as a fixed box to the static HTML page of ``orientviz view --export``, which
  otherwise holds the scene only.

The panel's text is Markdown with the legend's colours as HTML spans
(:func:`orientviz.viewer.legend.swatch`); :func:`runs` reads it back into coloured runs.
"""

from __future__ import annotations

import html
import io
import re
from typing import Any

import numpy as np
from numpy.typing import NDArray

_SPAN = re.compile(r'<span style="color: rgb\((\d+),(\d+),(\d+)\)">(.*?)</span>')

#: Width of the legend column of the PNG (px) and its font size.
LEGEND_WIDTH: int = 460
FONT_SIZE: int = 15


def runs(markdown: str) -> list[list[tuple[tuple[int, int, int] | None, str]]]:
    """Lines of (colour or None, text) runs of the panel's Markdown (``**``/``*`` dropped)."""
    out = []
    for line in re.split(r"  \n|\n", markdown):
        line = line.replace("**", "").replace("*", "")
        parts: list[tuple[tuple[int, int, int] | None, str]] = []
        pos = 0
        for m in _SPAN.finditer(line):
            if m.start() > pos:
                parts.append((None, html.unescape(line[pos : m.start()])))
            parts.append(((int(m[1]), int(m[2]), int(m[3])), html.unescape(m[4])))
            pos = m.end()
        if pos < len(line):
            parts.append((None, html.unescape(line[pos:])))
        out.append(parts)
    return out


def _font(size: int) -> Any:
    from matplotlib import font_manager  # GUI library: loaded when a PNG is made
    from PIL import ImageFont  # GUI library: loaded when a PNG is made

    return ImageFont.truetype(font_manager.findfont("DejaVu Sans"), size)


def _wrap(draw: Any, parts: list, font: Any, width: int) -> list[list]:
    """Break one line of runs into lines no wider than ``width`` px (at spaces)."""
    lines: list[list] = [[]]
    x = 0.0
    for colour, text in parts:
        for word in re.split(r"(\s+)", text):
            if not word:
                continue
            w = draw.textlength(word, font=font)
            if x + w > width and x > 0 and not word.isspace():
                lines.append([])
                x = 0.0
            if x == 0 and word.isspace():
                continue
            lines[-1].append((colour, word))
            x += w
    return lines


def view_png(render: NDArray[np.uint8], panel: str, title: str = "") -> bytes:
    """The rendered view (h, w, 3|4) uint8 with the panel's text (legend, read-out) on the right.

    Returns the PNG file's bytes.
    """
    from PIL import Image, ImageDraw  # GUI library: loaded when a PNG is made

    rgba = np.asarray(render, np.uint8)
    img = Image.fromarray(rgba[..., :3])
    if rgba.shape[-1] == 4:  # the canvas is transparent where nothing is drawn: white there
        img = Image.alpha_composite(
            Image.new("RGBA", img.size, (255, 255, 255, 255)), Image.fromarray(rgba)
        ).convert("RGB")
    font, bold = _font(FONT_SIZE), _font(FONT_SIZE + 3)
    probe = ImageDraw.Draw(img)
    rows: list[tuple[Any, list]] = [(bold, [[(None, title)]])] if title else []
    for parts in runs(panel.replace("σ̂", "σ")):  # the combining hat does not render
        rows.append((font, _wrap(probe, parts, font, LEGEND_WIDTH - 24)))
    step = int(FONT_SIZE * 1.45)
    height = max(img.height, 16 + sum(len(ls) for _, ls in rows) * step + 16)
    out = Image.new("RGB", (img.width + LEGEND_WIDTH, height), (255, 255, 255))
    out.paste(img, (0, 0))
    draw = ImageDraw.Draw(out)
    draw.line([(img.width, 0), (img.width, height)], fill=(200, 200, 200), width=1)
    y = 12
    for f, lines in rows:
        for line in lines:
            x = img.width + 12
            for colour, text in line:
                draw.text((x, y), text, font=f, fill=colour or (20, 20, 20))
                x += draw.textlength(text, font=f)
            y += step
    buf = io.BytesIO()
    out.save(buf, format="PNG")
    return buf.getvalue()


def panel_text(panel: Any) -> str:
    """The read-out (σ̂0, state, largest residual) and legend of a block panel, as Markdown."""
    return panel.handles["stats"].content + "  \n" + panel.handles["legend"].content


def panel_markdown(app: Any) -> str:
    """:func:`panel_text` of a running viewer (empty without a block panel)."""
    return "" if app.panel is None else panel_text(app.panel)


def with_panel(page: str, title: str, markdown: str) -> str:
    """The exported HTML ``page`` with a box holding ``title`` and the panel's ``markdown``."""
    if not markdown and not title:
        return page
    body = markdown.replace("  \n", "<br>\n")
    body = re.sub(r"\*\*(.+?)\*\*", r"<b>\1</b>", body)
    body = re.sub(r"(?<![\w*])\*(?!\s)(.+?)\*(?!\w)", r"<i>\1</i>", body)
    box = (
        '<div id="orientviz-panel" style="position: fixed; top: 12px; right: 12px; z-index: 10; '
        "max-width: 420px; background: rgba(255,255,255,0.93); border: 1px solid #ccc; "
        'border-radius: 6px; padding: 10px 12px; font: 13px/1.45 sans-serif; color: #222">'
        f"<b>{html.escape(title)}</b><br>\n{body}</div>"
    )
    at = page.rfind("</body>")
    return page[:at] + box + page[at:] if at >= 0 else page + box
