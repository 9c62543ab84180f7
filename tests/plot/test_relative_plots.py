"""Figures of relative orientation: each draws and returns a Figure (Agg)."""

from __future__ import annotations

import numpy as np
import pytest

mpl = pytest.importorskip("matplotlib")
mpl.use("Agg")

from orientviz.orientation import relative as rel  # noqa: E402
from orientviz.orientation import schemes as sch  # noqa: E402
from orientviz.orientation.plotter import preorientation_error  # noqa: E402
from orientviz.plot import relative as pr  # noqa: E402


def test_influence_and_precision_figures():
    s = sch.kovarik9()
    X, Y, Z = s.model_points(220.7, 240.0, -366.0)
    fig = pr.plot_influence(sch.influence(rel.design_dependent(X, Y, Z, 220.7)), s.labels)
    # the zero influences (φ and κ from the middle profile) are marked
    assert sum(t.get_text() == "0" for t in fig.axes[0].texts) >= 6
    tab = {
        n: sch.scheme_precision(n, 220.7, 240.0, -366.0, 0.005)[0] for n in ("gruber6", "kovarik9")
    }
    fig = pr.plot_scheme_precision(tab)
    assert len(fig.axes[0].patches) == 6


def test_relief_and_preorientation_figures():
    tab = {"exact": ([0.05, 0.1], np.array([3.0, 3.0]), np.array([3, 3]), np.array([3, 4]))}
    fig = pr.plot_passes_vs_relief(tab, paper=[(0.06, 2, 3), (0.10, 4, 4)])
    assert fig.axes[0].get_xlabel().startswith("relative relief")
    fig = pr.plot_preorientation_error(preorientation_error([10.0, 100.0]))
    assert fig.axes[0].get_xscale() == "log"
    # draws into a given axes
    import matplotlib.pyplot as plt

    f, ax = plt.subplots()
    assert pr.plot_preorientation_error(preorientation_error([10.0]), ax=ax) is f
