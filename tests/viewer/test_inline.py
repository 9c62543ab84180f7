"""The inline viewer helper: a static picture and a live server on 127.0.0.1 that stops."""

from __future__ import annotations

import socket

import numpy as np
import pytest

pytest.importorskip("viser")
pytest.importorskip("matplotlib")

import orientviz as ov
from orientviz.viewer.inline import scene_figure, show_inline  # noqa: E402


@pytest.fixture(scope="module")
def block():
    return ov.simulate_block(1, 4, rng=4, gross={"count": 1, "size_mm": 0.05}).block


def test_scene_figure_draws_cameras_points_and_residuals(block):
    import matplotlib.pyplot as plt

    fig = scene_figure(block, exaggeration=1000.0)
    ax = fig.axes[0]
    fig.canvas.draw()  # 3D collections hold their projected segments after a draw
    segs = [c for c in ax.collections if c.__class__.__name__ == "Line3DCollection"]
    assert len(segs) == 2
    assert len(segs[0].get_segments()) == 8 * block.n_images  # frustum edges
    assert len(segs[1].get_segments()) == block.n_observations  # one vector per ray
    assert "×1,000" in ax.get_title()
    plt.close(fig)


def test_show_inline_serves_locally_and_stops(block, capsys):
    app = show_inline(block, picture=False)
    try:
        assert app.host == "127.0.0.1" and app.port > 0
        with socket.create_connection(("127.0.0.1", app.port), timeout=5):
            pass
        assert str(app.port) in capsys.readouterr().out  # the IFrame's repr names the URL
    finally:
        app.stop()
    with pytest.raises(OSError):
        socket.create_connection(("127.0.0.1", app.port), timeout=2).close()
    assert np.isfinite(block.images.X0).all()
