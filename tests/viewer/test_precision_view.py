"""Confidence ellipsoids and neighbour correlations (no viser), and the panel's Precision folder."""

import numpy as np
import pytest

import orientviz as ov
from orientviz.viewer.precision_view import (
    confidence_factor,
    heat_strip,
    neighbour_correlations,
    point_covariances,
    station_covariances,
)

from .dense_bundle import small_bundle


def test_confidence_factor_holds_the_chosen_share():
    assert confidence_factor(0.95) == pytest.approx(2.7955, abs=1e-4)
    assert confidence_factor(0.1987) == pytest.approx(1.0, abs=1e-3)  # the 1σ sphere
    z = np.random.default_rng(0).normal(size=(200_000, 3))
    r = np.linalg.norm(z, axis=1)
    for level in (0.683, 0.9, 0.99):
        assert np.mean(r <= confidence_factor(level)) == pytest.approx(level, abs=0.004)
    with pytest.raises(ValueError):
        confidence_factor(1.0)


def test_neighbour_correlations_agree_with_the_dense_inverse(block):
    block.observations.xy += np.random.default_rng(4).normal(0, 0.004, block.observations.xy.shape)
    block.points.role[block.points.role == 2] = 0
    res = ov.bundle_adjust(block)  # selected blocks (exterior_pairs)
    dense = small_bundle(block)  # the same problem, dense Q = N⁻¹
    C = dense.correlations()
    m = block.n_images
    nb, rho = neighbour_correlations(res, 1, m)
    assert set(nb.tolist()) <= set(range(m)) - {1} and nb.size >= 2
    for j, r in zip(nb, rho):
        ref = C[6 * 1 : 6 * 1 + 6, 6 * j : 6 * j + 6]
        np.testing.assert_allclose(r, ref, atol=2e-4)
    strength = np.nanmax(np.abs(rho), axis=(1, 2))
    assert np.all(np.diff(strength) <= 0)  # most correlated first
    # station and point covariances: σ̂0² × the dense diagonal blocks
    idx, S = station_covariances(res, np.arange(m))
    np.testing.assert_allclose(S[2], dense.covariance()[12:15, 12:15], rtol=1e-3)
    pts = np.flatnonzero(block.points.role == 0)
    idx, S = point_covariances(res, pts)
    np.testing.assert_array_equal(idx, pts)
    fixed = np.flatnonzero(block.points.role == 1)
    assert point_covariances(res, fixed)[0].size == 0  # fixed control: none drawn


def test_heat_strip_draws_abs_rho():
    rho = np.zeros((2, 6, 6))
    rho[1, 2, 3] = -1.0
    img = heat_strip(rho, cell=4, gap=2)
    assert img.shape == (24, 2 * 24 + 2, 3)
    assert np.all(img[1:-1, 1:23] == 255)  # ρ = 0: white (inside the grey frame)
    assert np.all(img[0, :24] == 150) and np.all(img[:, 24:26] == 255)  # frame, gap
    cell = img[2 * 4 + 1, 26 + 3 * 4 + 1]
    assert cell[0] < 150 and cell[1] < 40  # |ρ| = 1: dark red


@pytest.fixture
def app():
    pytest.importorskip("viser")
    from orientviz.viewer.app import ViewerApp
    from orientviz.viewer.demos import demo_from_block

    a = ViewerApp(demo_from_block(ov.simulate_block(2, 5, rng=3).block), port=0, verbose=False)
    a.panel.adjust(50)
    yield a
    a.stop()


def test_precision_folder_draws_what_is_chosen(app):
    p = app.panel
    sc, h = p.scene, p.precision.handles
    st = p.state
    h["points"].value = "selected image"
    p.handles["image"].value = 3
    seen = np.unique(st.block.observations.point[st.block.observations.image == 3])
    free = seen[st.block.points.role[seen] != 1]
    assert np.asarray(sc.nodes["ellipsoids"].vertices).shape[0] == 42 * free.size
    nb = p.precision.neighbours
    assert nb.size >= 2
    assert np.asarray(sc.nodes["station_ellipsoids"].vertices).shape[0] == 162 * (1 + nb.size)
    assert h["strip"].visible and str(st.block.images.ids[nb[0]]) in h["strip_text"].content
    v95 = np.asarray(sc.nodes["ellipsoids"].vertices, dtype=float)
    h["level"].value = "99 %"
    v99 = np.asarray(sc.nodes["ellipsoids"].vertices, dtype=float)
    c = v95.reshape(-1, 42, 3).mean(axis=1, keepdims=True)  # the centres stay
    ratio = np.linalg.norm(v99.reshape(-1, 42, 3) - c, axis=2) / np.linalg.norm(
        v95.reshape(-1, 42, 3) - c, axis=2
    )
    np.testing.assert_allclose(ratio, confidence_factor(0.99) / confidence_factor(0.95), rtol=1e-4)
    assert "k = 3.37" in h["info"].content
    h["stations"].value = False
    assert "station_ellipsoids" not in sc.nodes
    h["points"].value = "none"
    assert "ellipsoids" not in sc.nodes
