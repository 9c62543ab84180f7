"""The inline viewer helper: a static picture and a live server on 127.0.0.1 that stops."""

from __future__ import annotations

import socket

import numpy as np
import pytest

pytest.importorskip("viser")
pytest.importorskip("matplotlib")

import orientviz as ov
from orientviz.block import CONTROL
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


def test_scene_figure_axes_read_object_coordinates(block):
    import matplotlib.pyplot as plt

    fig = scene_figure(block)
    ax = fig.axes[0]
    b = block
    # the heights of the points and of the projection centres lie inside the Z axis' range
    z_lo, z_hi = ax.get_zlim()
    assert z_lo <= b.points.xyz[:, 2].min() + 1.0 and b.images.X0[:, 2].max() - 1.0 <= z_hi
    x_lo, x_hi = ax.get_xlim()
    assert x_lo <= b.images.X0[:, 0].min() and b.images.X0[:, 0].max() <= x_hi
    # the control points are drawn where they are
    ctrl = [c for c in ax.collections if c.get_label() == "control points"]
    assert len(ctrl) == 1
    xs, ys, zs = ctrl[0]._offsets3d
    known = b.points.xyz[b.points.role == CONTROL]
    np.testing.assert_allclose(np.sort(np.asarray(zs)), np.sort(known[:, 2]), atol=1e-6)
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
