"""Figures of deformation fields and gross-error detection (Agg backend)."""

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from orientviz.adjust import gauss_newton  # noqa: E402
from orientviz.adjust.gross import data_snooping, engine_solver, reliability  # noqa: E402
from orientviz.block import systematic as se  # noqa: E402
from orientviz.block.deformation import image_field, model_field  # noqa: E402
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
