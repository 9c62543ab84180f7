"""Figures of the adjustment report (``orientviz solve FILE --report report.html``).

Each function takes the plain arrays that :func:`orientviz.report.build_report`
collects in ``Report.plot`` and returns a :class:`matplotlib.figure.Figure` (built
without pyplot, so no global figure state and no GUI backend). :func:`report_figures`
makes all that apply; :func:`png_bytes` encodes one. Big blocks are thinned to at most
``max_points`` plotted points so that the embedded PNGs stay small.
"""

from __future__ import annotations

import io
from collections.abc import Callable
from typing import Any

import numpy as np

#: Colours of the point roles (0 tie, 1 control, 2 check), as in :mod:`orientviz.plot.block`.
ROLE_COLOURS = {0: "0.6", 1: "#c0392b", 2: "#8e44ad"}
#: Blue of the report's figures.
BLUE = "#1f4e79"


def plain_text(text: object, limit: int = 40) -> str:
    """A user's id as literal figure text: ``$`` escaped (no mathtext), one line, short.

    matplotlib reads a text with two ``$`` as mathtext, so an id such as
    ``$\\undefinedmacro$`` would stop the figure; ids come from the user's files.
    """
    flat = " ".join(str(text).split())
    flat = flat.encode("utf-8", "backslashreplace").decode("utf-8")
    if len(flat) > limit:
        flat = flat[: limit - 1] + "…"
    return flat.replace("$", r"\$")


def _figure(w: float = 9.0, h: float = 5.2):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(w, h), layout="constrained")
    return fig


def _thin(n: int, max_points: int) -> np.ndarray:
    """Indices of at most ``max_points`` of ``n`` items (every k-th; deterministic)."""
    if n <= max_points:
        return np.arange(n)
    return np.linspace(0, n - 1, max_points).round().astype(np.int64)


def _nice(x: float) -> float:
    """A round number (1, 2 or 5 × 10^k) not larger than ``x``."""
    if not np.isfinite(x) or x <= 0:
        return 1.0
    e = np.floor(np.log10(x))
    for m in (5.0, 2.0, 1.0):
        if m * 10**e <= x:
            return float(m * 10**e)
    return float(10**e)


#: A point farther from the points' centre than this many times their radius
#: (:func:`framed`), or a projection centre so far from the other centres, is left out of
#: the overview's frame and counted in its legend: a far point (rays that meet near
#: infinity, a wrong coordinate) would otherwise shrink the whole block to a dot.
OUTSIDE_FRAME = 5.0

#: Coordinates of this size or more are outside every frame: no length unit gives them a
#: meaning, and a plot's axis cannot be ticked across them.
HUGE_COORDINATE = 1e100


def framed(xy: np.ndarray) -> np.ndarray:
    """Which of the planimetric positions ``xy`` (n, 2) lie inside their own frame.

    The centre is the positions' median; their radius is the 95th percentile of their
    distances from it, but at most four times the median distance (so a few wild
    positions among few do not set it); a position is inside when its distance is at most
    :data:`OUTSIDE_FRAME` radii. Non-finite positions and coordinates of
    :data:`HUGE_COORDINATE` or more are outside.

    Parameters
    ----------
    xy : ndarray, shape (n, 2)
        Positions in the block's length unit.

    Returns
    -------
    ndarray of bool, shape (n,)
    """
    xy = np.asarray(xy, float).reshape(-1, 2)
    ok = np.all(np.abs(xy) < HUGE_COORDINATE, axis=1)  # False for nan and inf too
    inside = np.zeros(xy.shape[0], bool)
    if not ok.any():
        return inside
    offset = xy[ok] - np.median(xy[ok], axis=0)
    d = np.hypot(offset[:, 0], offset[:, 1])
    radius, median = np.percentile(d, 95), np.median(d)
    if median > 0:
        radius = min(radius, 4.0 * median)
    inside[ok] = d <= OUTSIDE_FRAME * radius if radius > 0 else d == 0
    return inside


def _overview_frame(
    X0: np.ndarray, foot: np.ndarray | None, xy: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Which projection centres (m,) and which points (p,) the overview draws.

    The centres are framed among themselves and the points among themselves
    (:func:`framed`): cameras around an object lie far outside the points' own frame, and
    are drawn. A point within the box of the drawn centres and their footprints is drawn.
    """
    in_X0 = framed(X0[:, :2])
    in_xy = framed(xy)
    if in_X0.any():
        box = [X0[in_X0, :2]]
        if foot is not None:
            f = foot[in_X0].reshape(-1, 2)
            box.append(f[np.all(np.abs(f) < HUGE_COORDINATE, axis=1)])
        box = np.vstack(box)
        lo, hi = box.min(axis=0), box.max(axis=0)
        in_xy |= np.all((xy >= lo) & (xy <= hi), axis=1)
    return in_X0, in_xy


def overview_figure(
    overview: dict[str, Any], check: dict[str, Any] | None = None, *, max_points: int = 20000
):
    """Block overview: footprints, projection centres, points, check-point vectors.

    Parameters
    ----------
    overview : dict
        ``X0`` (m, 3) m, ``footprints`` (m, 4, 2) m or None, ``xy`` (p, 2) m, ``role``
        (p,), ``ids_images``; optional ``length_unit`` (axis labels, default m) and
        ``aerial`` (False: a plan view of a block that was not flown, default True).
    check : dict, optional
        ``xy`` (k, 2) and ``d`` (k, 3) differences estimated − given in m; drawn as
        exaggerated planimetric vectors with a scale arrow, ΔZ written beside them.
    max_points : int
        At most this many tie points are drawn.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.collections import PolyCollection

    fig = _figure(9.0, 6.0)
    ax = fig.add_subplot()
    foot = overview.get("footprints")
    X0 = np.asarray(overview["X0"], float)
    xy = np.asarray(overview["xy"], float)
    role = np.asarray(overview["role"])
    cxy = np.asarray(check["xy"], float).reshape(-1, 2) if check is not None else np.empty((0, 2))
    in_X0, inside = _overview_frame(X0, foot, np.vstack([xy, cxy]))
    in_xy, in_check = inside[: len(xy)], inside[len(xy) :]
    many = X0.shape[0] > 60
    if foot is not None:
        ok = np.all(np.isfinite(foot), axis=(1, 2)) & in_X0
        ax.add_collection(
            PolyCollection(
                foot[ok],
                facecolor=(0.12, 0.31, 0.47, 0.06 if many else 0.08),
                edgecolor=(0.12, 0.31, 0.47, 0.18 if many else 0.45),
                linewidth=0.4 if many else 0.7,
            )
        )
    tie = np.flatnonzero(in_xy & (role == 0))
    tie = tie[_thin(tie.size, max_points)]
    ax.scatter(
        xy[tie, 0],
        xy[tie, 1],
        s=1 if tie.size > 2000 else 9,
        c=ROLE_COLOURS[0],
        alpha=0.5 if tie.size > 2000 else 1.0,
        lw=0,
        label=f"tie points ({int(np.sum(role == 0))})",
        zorder=2,
    )
    ctl = np.flatnonzero(in_xy & (role == 1))
    ax.scatter(
        xy[ctl, 0],
        xy[ctl, 1],
        s=46,
        marker="^",
        c=ROLE_COLOURS[1],
        lw=0.5,
        edgecolor="white",
        label=f"control points ({ctl.size})",
        zorder=4,
    )
    chk = np.flatnonzero(in_xy & (role == 2))
    ax.scatter(
        xy[chk, 0],
        xy[chk, 1],
        s=40,
        marker="s",
        facecolor="none",
        edgecolor=ROLE_COLOURS[2],
        lw=1.4,
        label=f"check points ({chk.size})",
        zorder=4,
    )
    ax.scatter(
        X0[in_X0, 0],
        X0[in_X0, 1],
        s=3 if many else 14,
        c=BLUE,
        marker="o",
        lw=0,
        label=f"projection centres ({int(in_X0.sum())})",
        zorder=3,
    )
    ids = overview.get("ids_images") or []
    if 0 < len(ids) <= 24:
        for k in np.flatnonzero(in_X0):
            ax.annotate(
                plain_text(ids[k]),
                X0[k, :2],
                xytext=(3, 3),
                textcoords="offset points",
                fontsize=8,
                color=BLUE,
            )
    out_xy = np.all(np.isfinite(xy), axis=1) & ~in_xy
    out_X0 = np.all(np.isfinite(X0[:, :2]), axis=1) & ~in_X0
    if out_xy.any() or out_X0.any():
        what = [
            f"{int(n)} {w}"
            for n, w in ((out_xy.sum(), "point(s)"), (out_X0.sum(), "centre(s)"))
            if n
        ]
        drawn = np.vstack([X0[in_X0, :2], xy[in_xy]])
        centre = np.median(drawn, axis=0) if len(drawn) else np.zeros(2)
        far = np.vstack([xy[out_xy], X0[out_X0, :2]]) - centre
        reach = f"{float(np.max(np.abs(far))):.2g} {overview.get('length_unit', 'm')}"
        label = f"{' and '.join(what)} outside this frame\n(up to {reach} from the centre)"
        ax.plot([], [], ls="none", label=label)
    allxy = np.vstack(
        [xy[in_xy], X0[in_X0, :2]] + ([foot[in_X0].reshape(-1, 2)] if foot is not None else [])
    )
    allxy = allxy[np.all(np.isfinite(allxy), axis=1)]
    extent = float(np.max(np.ptp(allxy, axis=0))) if allxy.size else 1.0
    if check is not None:
        d = np.asarray(check["d"], float)
        ok = np.isfinite(np.hypot(d[:, 0], d[:, 1])) & in_check
        if ok.any():
            dmax = float(np.max(np.hypot(d[ok, 0], d[ok, 1])))
            ex = _nice(0.12 * extent / dmax) if dmax > 0 else 1.0
            ax.quiver(
                cxy[ok, 0],
                cxy[ok, 1],
                d[ok, 0] * ex,
                d[ok, 1] * ex,
                angles="xy",
                scale_units="xy",
                scale=1.0,
                color=ROLE_COLOURS[2],
                width=0.004,
                zorder=5,
            )
            ref = _nice(dmax) if dmax > 0 else 0.01
            unit, f = ("mm", 1000.0) if ref < 1 else ("m", 1.0)
            x0, y0 = allxy.min(axis=0) if allxy.size else (0.0, 0.0)
            y0 -= 0.06 * extent
            ax.annotate(
                "",
                xy=(x0 + ref * ex, y0),
                xytext=(x0, y0),
                arrowprops={"arrowstyle": "-|>", "color": ROLE_COLOURS[2], "lw": 1.5},
            )
            ax.text(
                x0 + ref * ex / 2,
                y0 - 0.015 * extent,
                f"{ref * f:g} {unit} (check-point vectors ×{ex:g})",
                ha="center",
                va="top",
                fontsize=8,
                color=ROLE_COLOURS[2],
            )
            if ok.sum() <= 30:
                for k in np.flatnonzero(ok & np.isfinite(d[:, 2])):
                    ax.annotate(
                        f"ΔZ {d[k, 2] * 1000:+.0f} mm",
                        cxy[k],
                        xytext=(5, -10),
                        textcoords="offset points",
                        fontsize=8,
                        color=ROLE_COLOURS[2],
                        zorder=6,
                        bbox={
                            "boxstyle": "round,pad=0.15",
                            "fc": "white",
                            "ec": "none",
                            "alpha": 0.8,
                        },
                    )
    ax.set_aspect("equal", adjustable="datalim")
    ax.autoscale_view()
    unit = overview.get("length_unit", "m")
    ax.set_xlabel(f"X [{unit}]")
    ax.set_ylabel(f"Y [{unit}]")
    ax.set_title(
        "Block overview: image footprints, projection centres, points"
        if overview.get("aerial", True)
        else "Plan view (X, Y): projection centres, points",
        fontsize=11,
    )
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    ax.grid(True, lw=0.3, alpha=0.5)
    return fig


def w_histogram_figure(data: dict[str, Any]):
    """Histogram of the normalised residuals with the critical value and N(0, 1).

    Parameters
    ----------
    data : dict
        ``w`` (n,) normalised residuals of the adjusted observations, ``critical``.
    """
    w = np.asarray(data["w"], float)
    w = w[np.isfinite(w)]
    crit = float(data["critical"])
    fig = _figure(9.0, 3.8)
    ax = fig.add_subplot()
    lim = min(max(crit * 1.3, float(np.max(np.abs(w), initial=0.0)) * 1.05, 4.0), 1e9)
    bins = np.linspace(-lim, lim, 61 if w.size > 200 else 31)
    ax.hist(w, bins=bins, color=BLUE, alpha=0.8, label=f"w ({w.size} observations)")
    t = np.linspace(-lim, lim, 300)
    ax.plot(
        t,
        np.exp(-0.5 * t**2) / np.sqrt(2 * np.pi) * w.size * (bins[1] - bins[0]),
        color="k",
        lw=1.0,
        label="N(0, 1)",
    )
    for s in (-1, 1):
        ax.axvline(s * crit, color="#c0392b", lw=1.2, ls="--")
    n_out = int(np.sum(np.abs(w) > crit))
    ax.text(
        crit,
        ax.get_ylim()[1] * 0.95,
        f" critical {crit:g}\n {n_out} above",
        color="#c0392b",
        va="top",
        fontsize=8,
    )
    ax.set_xlabel("normalised residual w = v / (σ √r)")
    ax.set_ylabel("count")
    ax.set_title("Normalised residuals", fontsize=11)
    ax.legend(fontsize=8, frameon=False, loc="upper left")
    return fig


def point_precision_figure(data: dict[str, Any], *, max_points: int = 8000):
    """Colour maps of the planimetric σ (r.m.s. of σX, σY) and of σZ of the points.

    Parameters
    ----------
    data : dict
        ``xy`` (p, 2) m, ``sigma`` (p, 3) in ``unit``.
    """
    xy = np.asarray(data["xy"], float)
    s = np.asarray(data["sigma"], float)
    unit = data["unit"]
    xu = unit if unit == "model units" else "m"  # the positions: m, or a model's own units
    k = _thin(xy.shape[0], max_points)
    xy, s = xy[k], s[k]
    fig = _figure(10.0, 4.4)
    axs = fig.subplots(1, 2)
    sxy = np.sqrt((s[:, 0] ** 2 + s[:, 1] ** 2) / 2)
    size = 6 if xy.shape[0] > 2000 else (20 if xy.shape[0] > 200 else 60)
    for ax, val, name in ((axs[0], sxy, "σXY = √((σX² + σY²)/2)"), (axs[1], s[:, 2], "σZ")):
        sc = ax.scatter(xy[:, 0], xy[:, 1], c=val, s=size, cmap="viridis", lw=0)
        fig.colorbar(sc, ax=ax, label=f"{name.split(' ')[0]} [{unit}]", shrink=0.9)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(f"X [{xu}]")
        ax.set_title(name, fontsize=10)
        ax.grid(True, lw=0.3, alpha=0.5)
    axs[0].set_ylabel(f"Y [{xu}]")
    fig.suptitle("Precision of the estimated points (a posteriori)", fontsize=11)
    return fig


def image_sigma_figure(data: dict[str, Any]):
    """Bars (lines for many images) of σX0, σY0, σZ0 and σω, σφ, σκ per image.

    Parameters
    ----------
    data : dict
        ``ids``, ``sigma_X0`` (m, 3) in ``length_unit``, ``sigma_angles`` (m, 3) in
        ``angle_unit``.
    """
    ids = list(data["ids"])
    m = len(ids)
    fig = _figure(10.0, 5.0)
    axs = fig.subplots(2, 1, sharex=True)
    x = np.arange(m)
    colours = ("#1f4e79", "#2e86c1", "#85c1e9")
    for ax, arr, names, unit in (
        (axs[0], data["sigma_X0"], ("σX0", "σY0", "σZ0"), data["length_unit"]),
        (axs[1], data["sigma_angles"], ("σω", "σφ", "σκ"), data["angle_unit"]),
    ):
        arr = np.asarray(arr, float)
        if m <= 60:
            w = 0.27
            for j in range(3):
                ax.bar(
                    x + (j - 1) * w,
                    np.nan_to_num(arr[:, j]),
                    width=w,
                    color=colours[j],
                    label=names[j],
                )
        else:
            for j in range(3):
                ax.plot(x, arr[:, j], color=colours[j], lw=0.8, label=names[j])
        ax.set_ylabel(f"[{unit}]")
        ax.legend(fontsize=8, frameon=False, loc="upper left", bbox_to_anchor=(1.005, 1.0))
        ax.grid(True, axis="y", lw=0.3, alpha=0.5)
    if m <= 40:
        axs[1].set_xticks(x, [plain_text(i) for i in ids], rotation=90 if m > 8 else 0, fontsize=8)
    else:
        axs[1].set_xlabel("image (index)")
    fig.suptitle("Precision of the exterior orientation per image (a posteriori)", fontsize=11)
    return fig


#: Figure name → function building it from ``Report.plot``.
FIGURES: dict[str, Callable[[dict[str, Any]], Any]] = {
    "overview": lambda plot: overview_figure(plot["overview"], plot.get("check")),
    "w_histogram": lambda plot: w_histogram_figure(plot["w_histogram"]),
    "point_precision": lambda plot: point_precision_figure(plot["point_precision"]),
    "image_sigma": lambda plot: image_sigma_figure(plot["image_sigma"]),
}


def png_bytes(fig, dpi: int = 90) -> bytes:
    """The figure as PNG bytes (the figure is not kept by any global state)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, facecolor="white")
    return buf.getvalue()


def report_figures(plot: dict[str, Any], names: list[str], dpi: int = 90) -> dict[str, bytes]:
    """PNG bytes of the named figures whose data is in ``plot`` (others are skipped).

    Parameters
    ----------
    plot : dict
        ``Report.plot`` of :func:`orientviz.report.build_report`.
    names : list of str
        Figure names (keys of :data:`FIGURES`).
    dpi : int
        Resolution of the PNGs.
    """
    out = {}
    for name in names:
        key = "overview" if name == "overview" else name
        if name in FIGURES and key in plot:
            out[name] = png_bytes(FIGURES[name](plot), dpi=dpi)
    return out
