"""Scene building on a real (browserless) viser server: names, positions, updates."""

from types import SimpleNamespace

import numpy as np

import orientviz as ov
from orientviz.viewer.block_geometry import COLORS, BlockGeometry
from orientviz.viewer.geometry import FLIP, matrix_from_wxyz
from orientviz.viewer.scene import BlockScene, image_node_name
from orientviz.viewer.state import BlockState


def build(server, block, **kw):
    geo = BlockGeometry(BlockState(block))
    return BlockScene(server.scene, geo, **kw).build()


def test_scene_tree_has_stable_names(server, block):
    sc = build(server, block)
    assert image_node_name(1, "img4") == "/block/strip_1/image_img4"
    for s, ident in zip(block.images.strip, block.images.ids):
        assert server.scene.get_handle_by_name(f"/block/strip_{s}/image_{ident}") is not None
    for name in ("points/tie", "points/control", "points/check", "rays/all", "rays/selected",
                 "residuals", "strips", "selected"):  # fmt: skip
        assert server.scene.get_handle_by_name(f"/block/{name}") is not None, name
    assert len(sc.image_nodes) == block.n_images


def test_frustum_apex_at_projection_centre(server, block):
    sc = build(server, block)
    frame = sc.geo.frame
    R = block.rotations()
    for k, h in enumerate(sc.image_nodes):
        np.testing.assert_allclose(
            np.asarray(h.position) + frame.origin, block.images.X0[k], atol=1e-9
        )
        # viser's camera frame is the image frame turned by diag(1, −1, −1)
        np.testing.assert_allclose(matrix_from_wxyz(h.wxyz), R[k] @ FLIP, atol=1e-9)


def test_points_by_role_in_scene_frame(server, block):
    sc = build(server, block)
    origin = sc.geo.frame.origin
    for role, r in (("tie", 0), ("control", 1), ("check", 2)):
        pts = np.asarray(sc.nodes[f"points/{role}"].points, dtype=float) + origin
        np.testing.assert_allclose(
            pts, block.points.xyz[block.points.role == r], atol=1e-3
        )  # float32


def test_residual_vectors_scale_with_exaggeration(server, block):
    state_block = block.copy()
    state_block.images.angles[2, 0] += ov.to_rad(0.05, "gon")  # misorient image 2 by 5 c
    sc = build(server, state_block, exaggeration=100.0)
    seg1 = np.asarray(sc.nodes["residuals"].points, dtype=float)
    sc.set_exaggeration(300.0)
    seg3 = np.asarray(sc.nodes["residuals"].points, dtype=float)
    np.testing.assert_allclose(seg3[:, 0], seg1[:, 0], atol=1e-3)
    v1, v3 = seg1[:, 1] - seg1[:, 0], seg3[:, 1] - seg3[:, 0]
    moved = np.linalg.norm(v1, axis=1) > 1.0
    assert moved.any()
    np.testing.assert_allclose(v3[moved], 3.0 * v1[moved], rtol=1e-4)  # float32 storage
    # only the rays of the misoriented image carry residuals (the others are exact)
    o = state_block.observations
    assert np.all(np.linalg.norm(v1[o.image != 2], axis=1) < 1e-3)
    assert np.all(np.linalg.norm(v1[o.image == 2], axis=1) > 0)


def test_update_moves_frustum_and_redraws_residuals(server, block):
    sc = build(server, block, exaggeration=50.0)
    before = np.asarray(sc.nodes["residuals"].points).copy()
    st = sc.geo.state
    st.set_exterior(1, X0=st.block.images.X0[1] + [3.0, 0.0, 0.0])
    stats = sc.update([1])
    after = np.asarray(sc.nodes["residuals"].points)
    np.testing.assert_allclose(
        np.asarray(sc.image_nodes[1].position) + sc.geo.frame.origin, st.block.images.X0[1]
    )
    changed = np.any(np.abs(after - before) > 1e-6, axis=(1, 2))
    np.testing.assert_array_equal(changed, st.block.observations.image == 1)
    assert stats["sigma0"] > 0
    # the quality colours go to the page decoded from sRGB, as it takes per-vertex colours
    from orientviz.viewer.shapes import vertex_colours

    col = sc.geo.residuals(50.0)[1]
    assert len(np.unique(col.reshape(-1, 3), axis=0)) > 1  # not all one colour
    np.testing.assert_array_equal(np.asarray(sc.nodes["residuals"].colors), vertex_colours(col))


def test_rays_of_selected_image(server, block):
    sc = build(server, block)
    sc.select(4)
    rays = np.asarray(sc.nodes["rays/selected"].points, dtype=float) + sc.geo.frame.origin
    o = block.observations
    assert rays.shape[0] == np.count_nonzero(o.image == 4)
    np.testing.assert_allclose(
        rays[:, 0], np.repeat(block.images.X0[4:5], rays.shape[0], 0), atol=1e-3
    )
    sc.set_rays("all")
    assert sc.nodes["rays/all"].visible and not sc.nodes["rays/selected"].visible
    assert np.asarray(sc.nodes["rays/all"].points).shape[0] == block.n_observations


def test_ellipsoids_after_adjustment(server, block):
    noisy = block.copy()
    noisy.observations.xy += np.random.default_rng(3).normal(0, 0.005, noisy.observations.xy.shape)
    st = BlockState(noisy)
    st.run()
    sc = BlockScene(server.scene, BlockGeometry(st)).build()
    assert "ellipsoids" in sc.nodes
    v = np.asarray(sc.nodes["ellipsoids"].vertices)
    # one ellipsoid (42 vertices) per tie point: control is fixed, the check point is
    # intersected after the bundle (no covariance)
    free = np.count_nonzero(block.points.role == 0)
    assert v.shape[0] == 42 * free


def test_large_blocks_batch_frustums_per_strip(server, block, monkeypatch):
    import orientviz.viewer.scene as scene_mod

    monkeypatch.setattr(scene_mod, "FRUSTUM_NODE_LIMIT", 2)
    sc = build(server, block)
    assert sc.image_nodes == []
    h0 = server.scene.get_handle_by_name("/block/strip_0/frustums")
    h1 = server.scene.get_handle_by_name("/block/strip_1/frustums")
    assert h0 is not None and h1 is not None
    seg0 = np.asarray(sc.strip_frustums[0][0].points, dtype=float) + sc.geo.frame.origin
    assert seg0.shape == (3 * 8, 2, 3)  # three images, eight edges each
    np.testing.assert_allclose(seg0[0, 0], block.images.X0[0], atol=1e-3)  # apex first
    before1 = np.asarray(sc.strip_frustums[1][0].points).copy()
    st = sc.geo.state
    st.set_exterior(0, X0=st.block.images.X0[0] + [0.0, 0.0, 20.0])
    sc.update([0])
    seg0 = np.asarray(sc.strip_frustums[0][0].points, dtype=float) + sc.geo.frame.origin
    np.testing.assert_allclose(seg0[0, 0], st.block.images.X0[0], atol=1e-3)
    np.testing.assert_array_equal(np.asarray(sc.strip_frustums[1][0].points), before1)

    # colours always per vertex (a node switched from one colour to per-vertex colours is
    # drawn without them), decoded from sRGB as the page takes vertex colours
    from orientviz.viewer.shapes import vertex_colours

    col = np.asarray(h1.colors)
    assert col.shape == (3 * 8, 2, 3)
    np.testing.assert_array_equal(
        col, np.broadcast_to(vertex_colours(COLORS["frustum"]), col.shape)
    )
    rgb = np.tile(np.array(COLORS["frustum"], np.uint8), (block.n_images, 1))
    rgb[4] = (220, 40, 40)
    sc.colour_images(rgb)
    col = np.asarray(h1.colors).reshape(3, 16, 3)  # images 3, 4, 5: 16 vertices each
    np.testing.assert_array_equal(col[1], np.tile(vertex_colours((220, 40, 40)), (16, 1)))
    np.testing.assert_array_equal(col[0], np.tile(vertex_colours(COLORS["frustum"]), (16, 1)))

    # a click into the scene selects the image whose frustum the clicked ray passes
    clicked = []
    sc.on_image_click = clicked.append
    frame = sc.geo.frame
    for k in (4, 0, 5, 3):
        apex = frame.to_scene(st.block.images.X0[k])
        eye = apex + np.array([30.0, -400.0, 250.0])  # looking at the apex from aside
        sc.scene_clicked(SimpleNamespace(ray_origin=tuple(eye), ray_direction=tuple(apex - eye)))
        # a ray that passes 15 % of the distance beside it (the background) selects nothing
        aside = apex + 0.15 * np.linalg.norm(apex - eye) * np.array([1.0, 0.0, 0.0])
        sc.scene_clicked(SimpleNamespace(ray_origin=tuple(eye), ray_direction=tuple(aside - eye)))
    assert clicked == [4, 0, 5, 3]


def test_a_role_without_points_gets_its_node_when_it_has_some(server, block):
    block.points.role[block.points.role == 2] = 0  # no check points
    sc = build(server, block)
    assert "points/check" not in sc.nodes  # no empty node (the page would compile its shader)
    assert server.scene.get_handle_by_name("/block/points/check") is None
    sc.set_visible("points", False)
    block = sc.geo.state.block
    block.points.role[7] = 2  # a point becomes a check point
    sc.update()
    node = sc.nodes["points/check"]
    np.testing.assert_allclose(
        np.asarray(node.points, dtype=float) + sc.geo.frame.origin, block.points.xyz[[7]], atol=1e-3
    )
    assert not node.visible  # made while the points are hidden: hidden too
    assert len(np.asarray(sc.nodes["points/tie"].points)) == np.count_nonzero(
        block.points.role == 0
    )
