"""The report's block overview frames the block, not its farthest point."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from orientviz.plot.report_figures import framed, overview_figure, png_bytes  # noqa: E402


def _block():
    gx, gy = np.meshgrid(np.linspace(0, 2000, 21), np.linspace(0, 1000, 11))
    xy = np.column_stack([gx.ravel(), gy.ravel()])
    X0 = np.column_stack([np.linspace(100, 1900, 10), np.full(10, 500.0), np.full(10, 1500.0)])
    return xy, X0


def test_framed_keeps_a_whole_block_and_leaves_out_far_and_broken_positions():
    xy, X0 = _block()
    assert framed(np.vstack([X0[:, :2], xy])).all()
    wild = np.array([[1000.0, 1e308], [5e8, 0.0], [np.nan, 3.0], [-1e308, -1e308]])
    inside = framed(np.vstack([X0[:, :2], xy, wild]))
    assert inside[: 10 + len(xy)].all() and not inside[-4:].any()
    # among few positions one wild coordinate does not set the frame either
    few = np.array([[0.0, 0.0], [100.0, 0.0], [0.0, 80.0], [60.0, 50.0], [1000.0, 1e308]])
    assert framed(few).tolist() == [True, True, True, True, False]


def test_overview_frames_the_block_and_counts_what_it_leaves_out():
    xy, X0 = _block()
    xy = np.vstack([xy, [[1000.0, 1e308], [5e8, 0.0]]])
    overview = {
        "X0": X0,
        "footprints": None,
        "xy": xy,
        "role": np.zeros(len(xy), int),
        "ids_images": [f"i{k}" for k in range(10)],
    }
    check = {  # a check point given at 1e308: its vector is left out, the other drawn
        "xy": np.array([[500.0, 500.0], [1000.0, 1e308]]),
        "d": np.array([[0.02, -0.01, 0.03], [0.0, -1e308, 0.05]]),
    }
    fig = overview_figure(overview, check)
    assert png_bytes(fig, dpi=40)[:4] == b"\x89PNG"  # drawn: no tick overflow at 1e308
    ax = fig.axes[0]
    assert np.ptp(ax.get_xlim()) < 5000 and np.ptp(ax.get_ylim()) < 5000
    assert len(ax.collections[-1].get_offsets()) == 1  # the one check vector drawn
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(t.startswith("2 point(s) outside this frame") and "1e+308 m" in t for t in labels)


def test_cameras_around_an_object_are_all_in_the_frame():
    """Close range: a dense object far inside the ring of cameras that photographed it."""
    rng = np.random.default_rng(3)
    xy = rng.normal(0, 0.1, (5000, 2))
    a = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    X0 = np.column_stack([2.5 * np.cos(a), 2.5 * np.sin(a), np.zeros(40)])
    overview = {"X0": X0, "footprints": None, "xy": xy, "role": np.zeros(5000, int)}
    ax = overview_figure(overview).axes[0]
    assert [len(c.get_offsets()) for c in ax.collections][-1] == 40  # every centre drawn
    assert not any("outside" in t.get_text() for t in ax.get_legend().get_texts())
