"""Plots and widget logic of the single-image and absolute-orientation lessons (Agg)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import orientviz as ov
from orientviz.orientation.examples import LAYOUTS, house, similarity_example  # noqa: E402
from orientviz.plot.conventions import plot_conventions, plot_frames, plot_image_frame  # noqa: E402
from orientviz.plot.image import plot_correlations, plot_image  # noqa: E402
from orientviz.plot.transform import control_kind, plot_transform_residuals  # noqa: E402
from orientviz.widgets.absolute import absolute_state, precision_table  # noqa: E402
from orientviz.widgets.resection import intersection_state, resection_state  # noqa: E402
from orientviz.widgets.rotation import describe, rotation_state  # noqa: E402


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def test_conventions_figure_and_given_axes():
    fig = plot_conventions()
    assert len(fig.axes) == 2
    fig2, ax = plt.subplots()
    assert plot_image_frame(ax=ax) is fig2
    fig3 = plt.figure()
    ax3 = fig3.add_subplot(projection="3d")
    assert plot_frames(ax=ax3) is fig3


def test_plot_image_draws_edges_and_residual_arrows():
    pts, edges = house()
    xy = ov.project(pts, [0, 0, 150.0], np.eye(3), 152.7)
    fig = plot_image(xy, edges=edges, residuals=np.full_like(xy, 0.004), labels=list("abcdefghij"))
    ax = fig.axes[0]
    assert len(ax.collections) == 2  # wireframe + quiver
    assert "largest 5.7 µm" in ax.texts[0].get_text()  # |(4, 4)| µm


def test_plot_transform_residuals_and_correlations():
    ex = similarity_example("separate", 0.05, rng=np.random.default_rng(0))
    res = ov.similarity_transform(ex.source, ex.target, sigma_target=0.05, point_ids=ex.ids)
    fig = plot_transform_residuals(res)
    ax = fig.axes[0]
    assert {t.get_text() for t in ax.texts} >= {"P1", "P5"}
    assert control_kind(res.used)[:5] == ["XY"] * 4 + ["Z"]
    fig = plot_correlations(res, names=["omega", "phi", "kappa"])
    assert fig.axes[0].images[0].get_array().shape == (3, 3)


def test_rotation_state_matches_library_and_sequences():
    st = rotation_state(10.0, -20.0, 150.0, unit="gon", sequence="opk")
    np.testing.assert_allclose(
        st.R, ov.matrix_from_opk(ov.to_rad(10.0), ov.to_rad(-20.0), ov.to_rad(150.0))
    )
    # the same matrix rebuilt from the other sequence's angles
    a = ov.to_rad(st.angles_other, "gon")
    np.testing.assert_allclose(ov.matrix_from_opk(*a, "pok"), st.R, atol=1e-12)
    assert not st.gimbal_lock
    assert "φ-ω-κ" in describe(st)
    # vertical view: the house ridge (points 8, 9) images along y, symmetric about x = 0
    v = rotation_state(0.0, 0.0, 0.0)
    np.testing.assert_allclose(v.xy[8, 0], 0.0, atol=1e-12)
    np.testing.assert_allclose(v.xy[8, 1], -v.xy[9, 1])


def test_rotation_state_gimbal_lock_and_behind_camera():
    assert rotation_state(0.0, 100.0, 30.0).gimbal_lock
    assert rotation_state(100.0, 30.0, 0.0, sequence="pok").gimbal_lock
    up = rotation_state(200.0, 0.0, 0.0)  # looking up at the sky: everything behind
    assert np.isnan(up.xy).all()


@pytest.mark.parametrize("layout", list(LAYOUTS))
def test_absolute_state_layouts(layout):
    ex, res = absolute_state(layout, 5.0, seed=3)
    assert res.converged
    text = precision_table(res)
    assert "σ̂0" in text and "ppm" in text
    # the estimate lies within 5 a-priori σ of the truth (σ = 5 cm noise)
    z = (res.x[:7] - ex.truth.params()) / np.where(res.std(False)[:7] > 0, res.std(False)[:7], 1)
    assert np.abs(z).max() < 5


def test_absolute_state_precision_ranks_layouts():
    std = {k: absolute_state(k, 5.0, 1)[1].std(False) for k in ("corners", "clustered", "strip")}
    # rotation across the strip is weak (ω for a strip along X) and clustered control
    # extrapolates: both worse than corners
    assert std["strip"][3] > 5 * std["corners"][3]
    assert std["clustered"][6] > 2 * std["corners"][6]


def test_resection_and_intersection_state():
    ex, res = resection_state(8, 80.0, 5.0, 1)
    assert res.converged and res.redundancy == 10
    ih = [intersection_state(bh).std()[1, 2] for bh in (0.3, 0.6)]
    # σ_Z ∝ H/B for the point between the images (exactly, in the normal case)
    assert ih[0] / ih[1] == pytest.approx(2.0, rel=1e-6)


def test_apps_build_without_a_browser():
    pytest.importorskip("ipywidgets")
    from orientviz.widgets.absolute import absolute_app
    from orientviz.widgets.resection import intersection_app, resection_app
    from orientviz.widgets.rotation import rotation_app

    for app in (rotation_app(), absolute_app(), resection_app()):
        assert len(app.children) == 2
    assert len(intersection_app().children) == 3
