"""Large real blocks in the viewer (issue 31 point 5): level of detail, precision on demand.

* above :data:`~orientviz.viewer.block_geometry.RESIDUAL_LIMIT` observations only the
  largest residual vectors are drawn, above ``RAY_LIMIT`` one ray in k of "all rays",
  and the legend says so;
* a block above :data:`~orientviz.viewer.solved.PRECISION_LIMIT` image observations is
  solved without the precision (same σ̂0 as ``solve``), the panel says so, and the
  precision follows on request;
* DBAT's ROMA bundle (60 images, 90 561 image points) opens as ``dbat_roma`` (at its start
  values while it is solved) and shows DBAT's σ0 once solved.
"""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.io.solve import load_named, solve_problem
from orientviz.viewer import block_geometry, solved
from orientviz.viewer.app import ViewerApp
from orientviz.viewer.block_geometry import BlockGeometry
from orientviz.viewer.legend import block_legend
from orientviz.viewer.quality import compute_quality
from orientviz.viewer.state import BlockState

from .conftest import tiny_block


@pytest.fixture
def noisy():
    return tiny_block(np.random.default_rng(3), noise_mm=0.01)


def test_level_of_detail_draws_the_largest_residuals_and_one_ray_in_k(noisy, monkeypatch):
    monkeypatch.setattr(block_geometry, "RESIDUAL_LIMIT", 5)
    monkeypatch.setattr(block_geometry, "RAY_LIMIT", 7)
    st = BlockState(noisy)
    geo = BlockGeometry(st)
    n = noisy.n_observations
    assert geo.residuals_drawn == (5, n)
    scores = st.scores()[0]
    seg, col = geo.residuals(1.0)
    assert seg.shape == (5, 2, 3) and col.shape == (5, 2, 3)
    # the drawn vectors start at the points of the five largest scores
    top = np.argsort(-scores)[:5]
    starts = geo.frame.to_scene(noisy.points.xyz[noisy.observations.point[np.sort(top)]])
    np.testing.assert_allclose(seg[:, 0], starts)
    k = int(np.ceil(n / 7))
    assert geo.ray_step == k and geo.rays().shape[0] == len(range(0, n, k))
    assert geo.rays(0).shape[0] == int(np.count_nonzero(noisy.observations.image == 0))


def test_the_selected_image_draws_one_ray_in_k_and_the_legend_says_so(noisy, monkeypatch):
    """A dense image's rays would paint a solid fan over its points: at most
    SELECTED_RAY_LIMIT of them are drawn, every k-th, and the legend names k and n."""
    from orientviz.viewer.legend import block_legend

    o = noisy.observations
    n0 = int(np.count_nonzero(o.image == 0))
    monkeypatch.setattr(block_geometry, "SELECTED_RAY_LIMIT", 4)
    geo = BlockGeometry(BlockState(noisy))
    k = int(np.ceil(n0 / 4))
    assert n0 > 4 and geo.selected_ray_step(0) == (k, n0)
    seg = geo.rays(0)
    want = np.flatnonzero(o.image == 0)[::k]
    assert seg.shape[0] == want.size <= 4
    np.testing.assert_allclose(seg[:, 1], geo.frame.to_scene(noisy.points.xyz[o.point[want]]))

    class Node:
        visible = True

    class Scene:  # what block_legend reads of a BlockScene
        nodes = {"rays/selected": Node()}
        selected = 0
        ellipsoids_visible = False
        selected_point = None

    Scene.geo = geo
    assert f"the selected image and its rays (one in {k} of its {n0:,}" in block_legend(Scene())
    monkeypatch.setattr(block_geometry, "SELECTED_RAY_LIMIT", 10_000)
    assert "one in" not in block_legend(Scene()) and geo.rays(0).shape[0] == n0


def test_rms_v_quality_needs_no_precision(noisy):
    st = BlockState(noisy)
    res = st.step(20, precision=False)
    assert res.normalized_residuals is None
    q = compute_quality(noisy, res, "rms_v")
    o = noisy.observations
    v = np.asarray(res.residuals)[: 2 * o.image.size].reshape(-1, 2) / o.sigma
    used = np.asarray(res.used_obs, bool)
    assert not used.all()  # the check point's rays are not adjusted: they do not count
    for i in range(noisy.n_images):
        mine = v[(o.image == i) & used]
        assert q.image[i] == pytest.approx(np.sqrt(np.mean(mine**2)), rel=1e-12)
    assert np.all(np.isnan(compute_quality(noisy, res, "rms_w").image))


def test_large_file_opens_without_precision_and_computes_it_on_request(monkeypatch):
    """dbat_camcal (2074 image points, lens model) with the limit lowered to 1000."""
    monkeypatch.setattr(solved, "PRECISION_LIMIT", 1000)
    want = solve_problem(load_named("dbat_camcal")).adjustment.sigma0
    app = ViewerApp("dbat_camcal", port=0, verbose=False)
    try:
        p = app.panel
        st = p.state
        assert not app.messages
        assert st.result.normalized_residuals is None
        assert st.sigma0() == pytest.approx(want, rel=1e-9)
        info = p.precision.handles["info"].content
        assert "precision not computed" in info and "1,000" in info
        assert "precision not computed" in p.handles["stats"].content
        assert p.precision.handles["compute"].visible
        assert not p.act.handles["auto_precision"].value
        p.precision.compute()
        assert st.result.normalized_residuals is not None and st.at_result
        assert st.sigma0() == pytest.approx(want, rel=1e-6)
        assert not p.precision.handles["compute"].visible
        assert "ellipsoids" in p.scene.nodes
        assert st.scores()[1] == "|w|"
    finally:
        app.stop()


@pytest.mark.slow
def test_dbat_roma_opens_with_dbats_sigma0_and_level_of_detail():
    from orientviz.reproduce.dbat_roma import paper_values

    app = ViewerApp("dbat_roma", port=0, verbose=False)
    try:  # every start value given: it opens at them while it is solved (test_background.py)
        assert app.background is not None and app.background.wait(300)
        st, sc = app.panel.state, app.scene
        b = st.block
        assert (b.n_images, b.n_points, b.n_observations) == (60, 26321, 90561)
        assert not app.messages and st.result.converged
        printed = paper_values()["summary||sigma0"]  # DBAT's report, 6 digits
        assert f"{st.sigma0():.6f}" == printed
        assert st.result.normalized_residuals is None  # the precision on request
        limit = block_geometry.RESIDUAL_LIMIT
        assert np.asarray(sc.nodes["residuals"].points).shape[0] == limit
        assert f"the {limit:,} largest of 90,561 residual vectors" in block_legend(sc)
        assert len(st.history) == st.result.iterations + 1  # every iteration replayable
    finally:
        app.stop()
