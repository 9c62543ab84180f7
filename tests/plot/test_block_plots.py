"""Block figures (orientviz.plot.block): they draw what they are given and return a Figure."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import orientviz as ov
from orientviz.plot.block import (  # noqa: E402
    plot_block_layout,
    plot_check_heights,
    plot_error_ellipses,
    plot_error_vectors,
    plot_height_law,
    plot_precision_map,
    plot_strip_law,
)
from orientviz.simulate import height_precision, planimetric_precision


@pytest.fixture(scope="module")
def sim():
    return ov.simulate_block(
        2, 5, rng=np.random.default_rng(1), extra=None, control="chains", chain_spacing=2, control_spacing=1,
        control_kind="xy+z", n_check=2,
    )  # fmt: skip


def test_layout_marks_every_control_kind(sim):
    fig = plot_block_layout(sim)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    for want in ("strip 0", "strip 1", "XY control", "Z control", "check points", "tie points"):
        assert want in labels
    # 10 footprints + model areas drawn as patches
    assert len(fig.axes[0].patches) >= 10 + 8
    plt.close(fig)


def test_error_vectors_into_given_axes(sim):
    fig0, ax = plt.subplots()
    est = sim.truth.points.xyz + 0.01
    fig = plot_error_vectors(est, sim.truth.points.xyz, ax=ax, control=sim.block.points.role == 1)
    assert fig is fig0
    assert "RMS X 0.010 m" in ax.get_title()
    plt.close(fig)


def test_error_ellipses_axes_follow_the_covariance():
    xy = np.array([[0.0, 0.0], [100.0, 0.0]])
    cov = np.array([np.diag([4.0, 1.0]), np.diag([1.0, 9.0])])
    fig = plot_error_ellipses(xy, cov, scale=1.0)
    coll = fig.axes[0].collections[0]
    # widths are 2·a (major), heights 2·b (minor) of the unscaled ellipses
    np.testing.assert_allclose(np.sort(coll._widths * 2), [4.0, 6.0])
    np.testing.assert_allclose(np.sort(coll._heights * 2), [2.0, 2.0])
    plt.close(fig)


def test_precision_map_and_laws():
    p = planimetric_precision(2)
    fig = plot_precision_map(p)
    assert "μ = " in fig.axes[0].get_title()
    plt.close(fig)
    fig = plot_strip_law([planimetric_precision(n) for n in (2, 3)])
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert any("log10" in t for t in labels) and any("< 2" in t for t in labels)
    plt.close(fig)
    hs = [height_precision(i, n_strips=2, models_per_strip=8) for i in (2, 4)]
    fig = plot_height_law(hs)
    assert len(fig.axes[0].lines) >= 3
    plt.close(fig)


@pytest.mark.parametrize("method", ["rigorous", "pat-m", "polynomial", "bundle"])
def test_widget_state_every_method(method):
    from orientviz.widgets.block import block_state

    st = block_state(2, 6, method=method, control="chains", spacing=2)
    # 5 µm image noise at 1:10 000 gives decimetre-level errors at most
    assert np.all(st.rms < 1.0) and st.rms.shape == (3,)
    assert method in st.summary()


def test_widget_app_builds():
    pytest.importorskip("ipywidgets")
    from orientviz.widgets.block import block_app

    box = block_app()
    assert len(box.children) == 2
    plt.close("all")


def test_check_heights_draw_each_result_at_the_true_x():
    from orientviz.bundle import bundle_adjust
    from orientviz.errors import InputError

    s = ov.simulate_block(2, 5, rng=4, n_check=8)
    truth = s.truth.points.xyz
    chk = np.flatnonzero(s.block.points.role == 2)
    wave = truth.copy()
    wave[:, 2] += 0.3 * np.sin(truth[:, 0] / 1000.0)  # m, a known height error along X
    gap = wave.copy()
    gap[chk[0]] = np.nan  # a check point without coordinates is left out
    adj = bundle_adjust(s.block)
    fig = plot_check_heights(s, {"wave": wave, "gap": gap, "bundle": adj})
    ax = fig.axes[0]
    lines = [ln for ln in ax.get_lines() if ln.get_marker() not in ("None", None, "")]
    assert len(lines) == 3
    np.testing.assert_allclose(lines[0].get_xdata(), truth[chk, 0] / 1000.0)  # km
    np.testing.assert_allclose(lines[0].get_ydata(), 0.3 * np.sin(truth[chk, 0] / 1000.0))
    np.testing.assert_allclose(lines[1].get_xdata(), truth[chk[1:], 0] / 1000.0)
    d_bundle = adj.points[chk, 2] - truth[chk, 2]
    np.testing.assert_allclose(lines[2].get_ydata(), d_bundle)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    mu = np.sqrt(np.mean((0.3 * np.sin(truth[chk, 0] / 1000.0)) ** 2))
    assert labels[0] == f"wave (μz {mu:.2f} m)" and labels[2].startswith("bundle (μz ")
    assert ax.get_xlabel() == "X along the strips [km]" and "[m]" in ax.get_ylabel()
    x0, x1 = ax.get_xlim()
    assert x0 <= truth[chk, 0].min() / 1000.0 and x1 >= truth[chk, 0].max() / 1000.0
    assert x1 - x0 < 20.0  # km, not m
    y0, y1 = ax.get_ylim()
    assert y0 < -0.2 and y1 > 0.2
    with pytest.raises(InputError, match="expected coordinates of all"):
        plot_check_heights(s, {"short": truth[:-1]})
    plt.close("all")
