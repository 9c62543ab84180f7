"""Scene data, plots and the slider logic (no browser)."""

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest

from orientviz.radar import geier1973 as G
from orientviz.radar import scene
from orientviz.radar.orientation import exterior
from orientviz.radar.ppi import sphere_radius
from orientviz.widgets.radar import RadarSliders

T = G.images()


def test_scene_data_shapes_and_geometry():
    P, xy = G.points("fig7"), G.image_coordinates("fig7", 2, rounded=False)
    st = scene.station_scene(T[2], "image 2", axis_length=1000.0)
    np.testing.assert_allclose(np.linalg.norm(st["axis"][1] - st["axis"][0]), 1000.0)
    c = scene.circle_scene(xy, T[2], n_vertices=9)
    assert c["polylines"].shape == (25, 9, 3)
    d = np.linalg.norm(c["polylines"] - c["centre"], axis=2)
    np.testing.assert_allclose(d, np.repeat(c["radii"][:, None], 9, axis=1))
    # every circle lies in its azimuth plane and passes through its object point
    np.testing.assert_allclose(
        np.einsum("nvj,nj->nv", c["polylines"] - c["centre"], c["normals"]), 0, atol=1e-6
    )
    tri = scene.trilateration_scene(P[[0, 4, 22]], sphere_radius(xy[[0, 4, 22]], T[2]))
    assert np.min(np.linalg.norm(tri["candidates"] - np.array(T[2].X0), axis=1)) < 1e-6
    res = scene.residual_scene(P, xy + 0.5, T[2], scale=100.0)
    np.testing.assert_allclose(res["image_residuals"], -0.5, atol=1e-9)
    pair = scene.pair_scene(G.image_coordinates("fig7", 1, rounded=False), T[1], xy, T[2], 5)
    np.testing.assert_allclose(pair["points"], P, atol=1e-5)
    assert pair["weak"].dtype == bool


def test_plots_return_figures():
    from orientviz.plot import radar as pr

    P, xy = G.points("fig7"), G.image_coordinates("fig7", 2)
    r = exterior(P, xy, T[2].with_(X0=(30000.0, 0.0, -1000.0), phi=0.0, omega=0.0, kappa=0.0))
    figs = [
        pr.plot_image(xy, T[2], residuals=r.residuals.reshape(-1, 2)),
        pr.plot_scene_3d([scene.station_scene(T[2])], [scene.circle_scene(xy[:3], T[2])], P),
        pr.plot_trilateration(
            scene.trilateration_scene(P[[0, 4, 22]], sphere_radius(xy[[0, 4, 22]], T[2]))
        ),
        pr.plot_correlations(r),
        pr.plot_fig8(np.arange(10.0), np.arange(10.0) + 0.1, spread=np.ones(10)),
    ]
    import matplotlib.pyplot as plt

    for f in figs:
        assert f.axes
        plt.close(f)


def test_sliders_move_the_image_and_solve_back():
    s = RadarSliders("plane", 2)
    assert np.abs(s.discrepancies()).max() <= 0.5  # true values: only the rounding
    s.set("X0", s.values["X0"] + 100.0)
    s.set("kappa", s.values["kappa"] + 0.5)
    assert np.abs(s.discrepancies()).max() > 50
    res = s.solve("exterior")
    assert res.converged
    assert abs(s.values["X0"] - 30054.47) < 0.5 and np.abs(s.discrepancies()).max() < 1.0
    lo, hi, step, val = s.slider_spec()["phi"]
    assert lo < val < hi and step > 0
    with pytest.raises(ValueError):
        s.set("nope", 1.0)
