"""The PPI image of a whole radar picture keeps its tick labels apart (Geier's images span ~100 km)."""

import matplotlib

matplotlib.use("Agg")

from orientviz.plot.radar import plot_image
from orientviz.radar import geier1973 as G


def _overlaps(labels) -> list[tuple[str, str]]:
    boxes = [
        (t.get_text(), t.get_window_extent()) for t in labels if t.get_visible() and t.get_text()
    ]
    return [
        (a, b) for i, (a, ba) in enumerate(boxes) for b, bb in boxes[i + 1 :] if ba.overlaps(bb)
    ]


def test_tick_labels_of_a_wide_image_do_not_overlap():
    fig = plot_image(G.image_coordinates("fig7", 2), G.images()[2])
    fig.canvas.draw()
    ax = fig.axes[0]
    assert ax.get_xlabel() == "x_B [km]"
    assert _overlaps(ax.get_xticklabels()) == []
    assert _overlaps(ax.get_yticklabels()) == []


def test_small_images_stay_in_metres():
    fig = plot_image([[10.0, 20.0], [-300.0, 150.0], [40.0, -90.0]])
    assert fig.axes[0].get_xlabel() == "x_B [m]"
