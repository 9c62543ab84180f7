"""The design studio's summary in words: the block's figures next to the accuracy law's
values, the method, the reliability figures and the weak spots (Markdown for the panel,
:meth:`orientviz.viewer.studio.Studio.summary_markdown`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..design import METHODS, DesignQuality, FlightDesign


def summary_markdown(
    quality: DesignQuality, block, design: FlightDesign | None, law: dict[str, Any],
    method: str, title: str | None = None,
) -> str:  # fmt: skip
    """The summary of a design as Markdown.

    Parameters
    ----------
    quality : DesignQuality
        The shown quality (its ``summary`` in m, MDB in mm; ``weak_spots``).
    block : Block
        The design block.
    design : FlightDesign or None
        The plan (None for a block from a file).
    law : dict
        The accuracy law's ``sigma_xy``, ``sigma_z`` (m, NaN: none) and ``note``.
    method : str
        A key of :data:`orientviz.design.METHODS`.
    title : str, optional
        What the block is (a file name) when there is no plan.
    """
    s = quality.summary
    mm = 1e3

    def lawv(key):
        v = law.get(key, float("nan"))
        return "–" if not np.isfinite(v) else f"{v * mm:.1f}"

    d = design
    if d is not None:
        head = (
            f"**{d.strips} strips × {d.images_per_strip} images**, 1:{d.scale:,.0f}, "
            f"p = {d.forward_overlap:.0%}, q = {d.side_overlap:.0%}, σ image "
            f"{d.sigma_image_mm * 1e3:.1f} µm, control σ {d.sigma_control * 100:.0f} cm"
            + (f", GNSS σ {d.sigma_gnss:.2f} m" if d.sigma_gnss else "")
            + (" (shift per strip)" if d.sigma_gnss and d.gnss_offsets else "")
            + (f", statoscope σ {d.sigma_statoscope:.2f} m" if d.sigma_statoscope else "")
            + (f", APR σ {d.sigma_apr:.2f} m" if d.sigma_apr else "")
        )
    else:
        head = f"**{title or 'a block'}**"
    b = block
    extra = b.n_images - (d.strips * d.images_per_strip if d is not None else b.n_images)
    head += (
        f"; {b.n_images} images"
        + (f" ({extra:+d} by cross strips / removals)" if extra else "")
        + f", {b.n_points} points, {s['n_control']} control points"
    )
    note = METHODS[method][1]
    lines = [
        head,
        "",
        f"Method: **{METHODS[method][0]}**" + (f" — {note}" if note else ""),
        "",
        "| | median | RMS | max | law (RMS) |",
        "| --- | --- | --- | --- | --- |",
        f"| σ_XY mm | {s['sigma_xy_median'] * mm:.1f} | {s['sigma_xy_rms'] * mm:.1f} | "
        f"{s['sigma_xy_max'] * mm:.1f} | {lawv('sigma_xy')} |",
        f"| σ_Z mm | {s['sigma_z_median'] * mm:.1f} | {s['sigma_z_rms'] * mm:.1f} | "
        f"{s['sigma_z_max'] * mm:.1f} | {lawv('sigma_z')} |",
        "",
    ]
    if np.isfinite(s["redundancy_mean"]):
        lines.append(
            f"mean redundancy number {s['redundancy_mean']:.2f}; largest MDB "
            f"{s['mdb_max_mm'] * 1e3:.0f} µm; largest δ̄0 {s['external_max']:.1f}; "
            f"{s['untestable_rays']} rays not testable.  "
        )
    else:
        lines.append(
            "Reliability (redundancy, MDB, δ̄0 of the image rays) is not defined for "
            "independent models: the models have no image rays.  "
        )
    lines.append(f"Law: {law.get('note', '')}")
    spots = quality.weak_spots
    if spots:
        lines += ["", "**Weak spots**"] + [f"- {w}" for w in spots]
    return "\n".join(lines)
