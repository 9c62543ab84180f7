"""The reliability map and MDB histogram of a bundle block (Agg backend)."""

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import orientviz as ov
from orientviz.bundle import ray_reliability
from orientviz.plot.gross import (  # noqa: E402
    plot_block_reliability,
    plot_mdb_histogram,
    plot_reliability_map,
)


@pytest.fixture(scope="module")
def case():
    sim = ov.simulate_block(3, 5, rng=4, n_check=6)
    adj = ov.bundle_adjust(sim.block)
    return sim.block, adj, ray_reliability(adj, sim.block)


def test_map_marks_the_untestable_points(case, tmp_path):
    import matplotlib.pyplot as plt

    block, adj, rel = case
    fig = plot_reliability_map(rel, block, xyz=adj["points"])
    ax = fig.axes[0]
    blind = np.unique(rel.point[rel.used & ~rel.testable])
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert f"not testable along the base ({blind.size} points)" in labels
    assert "µm" in fig.axes[1].get_ylabel()  # the colour bar
    fig2 = plot_reliability_map(rel, block, quantity="shift", layout=False)
    assert "cm" in fig2.axes[1].get_ylabel()
    with pytest.raises(ov.InputError, match="quantity"):
        plot_reliability_map(rel, block, quantity="redundancy")
    fig3 = plot_mdb_histogram(rel, block)
    n_blind = int((rel.used & ~rel.testable).sum())
    assert f"{n_blind} not testable" in fig3.axes[0].get_title()
    fig4 = plot_block_reliability(rel, block, xyz=adj["points"], title="block")
    fig4.savefig(tmp_path / "reliability.png")
    assert (tmp_path / "reliability.png").stat().st_size > 10_000
    plt.close("all")
