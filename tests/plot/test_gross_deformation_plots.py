"""Figures of deformation fields and gross-error detection (Agg backend)."""

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from orientviz.adjust import gauss_newton  # noqa: E402
from orientviz.adjust.gross import engine_solver, reliability  # noqa: E402
from orientviz.adjust.snooping import data_snooping  # noqa: E402
from orientviz.errors import InputError  # noqa: E402
from orientviz.plot.deformation import (  # noqa: E402
    plot_deformation_comparison,
    plot_image_field,
    plot_model_field,
)
from orientviz.plot.gross import (  # noqa: E402
    plot_cleaning,
    plot_normalized_residuals,
    plot_reliability,
)
from orientviz.simulate import image_field, model_field
from orientviz.simulate import systematic as se

T = np.linspace(0, 10, 40)


def _line(x):
    return x[0] + x[1] * T, np.column_stack([np.ones_like(T), T])


def test_deformation_figures(tmp_path):
    import matplotlib.pyplot as plt

    err = se.typical(10.0)
    fig = plot_image_field(image_field(err))
    assert "µm" in fig.axes[0].get_title()
    raw, cal = model_field(err), model_field(err, correction=se.affinity(3.0, 1.0))
    fig2 = plot_deformation_comparison(raw, cal)
    assert len(fig2.axes) == 6  # 4 panels + 2 colour bars
    fig2.savefig(tmp_path / "deformation.png")
    _, ax = plt.subplots()
    assert plot_model_field(raw, component="height", ax=ax) is ax.figure
    with pytest.raises(InputError, match="component"):
        plot_model_field(raw, component="twist")
    plt.close("all")


def test_gross_figures(tmp_path):
    import matplotlib.pyplot as plt

    rng = np.random.default_rng(42)
    l = 1 + 0.5 * T + rng.normal(0, 0.01, T.size)
    l[[5, 22]] += [0.08, -0.12]
    res = data_snooping(engine_solver(_line, [0.0, 0.0], l, 0.01), T.size)
    fig = plot_cleaning(res, truth=[5, 22, 30])
    assert "1 missed" in fig.axes[0].get_title()
    adj = gauss_newton(_line, [0.0, 0.0], l, 0.01)
    fig = plot_normalized_residuals(adj)
    assert "beyond" in fig.axes[0].get_title()
    fig = plot_reliability(reliability(adj))
    fig.savefig(tmp_path / "reliability.png")
    plt.close("all")


def test_deformation_frame_of_model_fields(tmp_path):
    import matplotlib.pyplot as plt
    from matplotlib.quiver import Quiver

    from orientviz.plot.deformation import plot_deformation_frame

    err = se.typical(10.0) + se.unflatness(8.0)
    raw, cal = model_field(err, n=5), model_field(err, correction=se.typical(10.0), n=5)
    ex = 2000.0
    for t, d in ((0.0, raw.d), (1.0, cal.d), (0.5, 0.5 * (raw.d + cal.d))):
        fig = plot_deformation_frame(raw, cal, t, exaggeration=ex)
        ax = fig.axes[0]
        (q,) = [c for c in ax.collections if isinstance(c, Quiver)]
        assert q.N == raw.xyz.shape[0] == 25  # one arrow per grid point
        # arrows start on the grid (m) and are the exaggerated planimetric deformation
        np.testing.assert_allclose(q.X, raw.xyz[:, 0])
        np.testing.assert_allclose(q.U, ex * d[:, 0], atol=1e-9)
        np.testing.assert_allclose(q.V, ex * d[:, 1], atol=1e-9)
        # points coloured by the true ΔZ (cm) on one scale for every frame
        (pts,) = [c for c in ax.collections if not isinstance(c, Quiver)]
        np.testing.assert_allclose(pts.get_array(), d[:, 2] * 100.0)
        lim = 100.0 * max(np.abs(raw.d[:, 2]).max(), np.abs(cal.d[:, 2]).max())
        assert pts.get_clim() == pytest.approx((-lim, lim))
        # data limits in m: the model area (a few km at 1 : 10 000), not mm
        x0, x1 = ax.get_xlim()
        assert x0 <= raw.xyz[:, 0].min() and x1 >= raw.xyz[:, 0].max()
        assert 500.0 < x1 - x0 < 3000.0
        assert "[m]" in ax.get_xlabel() and f"{t:.2f}" in ax.get_title()
        assert fig.axes[1].get_ylabel() == "ΔZ [cm]"  # the colour bar
    fig.savefig(tmp_path / "frame.png")
    with pytest.raises(InputError, match="t in"):
        plot_deformation_frame(raw, cal, 1.5)
    with pytest.raises(InputError, match="same grid"):
        plot_deformation_frame(raw, model_field(err, n=4), 0.0)
    plt.close("all")


def test_deformation_frame_of_image_fields():
    import matplotlib.pyplot as plt
    from matplotlib.quiver import Quiver

    from orientviz.plot.deformation import plot_deformation_frame

    a, b = image_field(se.radial(8.0), n=7), image_field(se.affinity(3.0, 1.0), n=7)
    fig = plot_deformation_frame(a, b, 0.0)
    ax = fig.axes[0]
    (q,) = [c for c in ax.collections if isinstance(c, Quiver)]
    assert q.N == 49
    # default exaggeration: the largest vector of the field at t = 0 is 1/8 of the width
    length = np.hypot(q.U, q.V)
    assert length.max() == pytest.approx(220.0 / 8.0)
    # the image format in mm (± 110 mm), not m or µm
    x0, x1 = ax.get_xlim()
    assert x0 <= -110.0 and x1 >= 110.0 and x1 - x0 < 300.0
    assert "[mm]" in ax.get_xlabel()
    (pts,) = [c for c in ax.collections if not isinstance(c, Quiver)]
    np.testing.assert_allclose(pts.get_array(), np.hypot(a.d[:, 0], a.d[:, 1]) * 1e3)
    plt.close("all")


def test_field_split_panels_share_one_exaggeration(tmp_path):
    import matplotlib.pyplot as plt
    from matplotlib.quiver import Quiver

    from orientviz.bundle import Ebner12
    from orientviz.plot.deformation import plot_field_split
    from orientviz.simulate import split_field

    tr = se.unflatness(8.0)
    s = split_field(tr, Ebner12(), n=9)
    fig = plot_field_split(s)
    axes = fig.axes
    assert len(axes) == 3
    quivers = [[c for c in ax.collections if isinstance(c, Quiver)][0] for ax in axes]
    ex = 220.0 / 8.0 / np.hypot(s.grid.d[:, 0], s.grid.d[:, 1]).max()
    part = s.described(s.grid.xy, np.zeros(81, np.int64))
    for q, d in zip(quivers, (s.grid.d, part, s.grid.d - part)):
        assert q.N == 81
        np.testing.assert_allclose(q.U, ex * d[:, 0], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(q.V, ex * d[:, 1], rtol=1e-12, atol=1e-12)
    # described + remainder arrows add up to the field's
    np.testing.assert_allclose(quivers[1].U + quivers[2].U, quivers[0].U, atol=1e-9)
    for ax, q in zip(axes, quivers):
        x0, x1 = ax.get_xlim()  # the image format in mm, one frame for all panels
        y0, y1 = ax.get_ylim()
        assert (x0, x1, y0, y1) == pytest.approx((*axes[0].get_xlim(), *axes[0].get_ylim()))
        assert x0 <= -110.0 and x1 >= 110.0 and x1 - x0 < 300.0
        # every arrow tip lies inside the axes
        assert x0 <= (q.X + q.U).min() and (q.X + q.U).max() <= x1
        assert y0 <= (q.Y + q.V).min() and (q.Y + q.V).max() <= y1
        assert "[mm]" in ax.get_xlabel() and "[mm]" in ax.get_ylabel()
    assert "described" in axes[1].get_title() and "remainder" in axes[2].get_title()
    assert f"{s.rms_um[2]:.2f} µm" in axes[2].get_title()
    assert f"{100 * s.share[0]:.0f} %" in axes[1].get_title()
    fig.savefig(tmp_path / "split.png")
    # a given exaggeration is used as it is
    fig2 = plot_field_split(s, exaggeration=1000.0)
    q = [c for c in fig2.axes[0].collections if isinstance(c, Quiver)][0]
    np.testing.assert_allclose(q.U, 1000.0 * s.grid.d[:, 0], atol=1e-12)
    plt.close("all")
