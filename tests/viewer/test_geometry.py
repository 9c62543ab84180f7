"""Pure scene geometry (no viser): frustums, residual offsets, quaternions, meshes."""

import numpy as np
import pytest

import orientviz as ov
from orientviz.viewer import geometry as g


@pytest.fixture
def rng():
    return np.random.default_rng(11)


def random_rotations(rng, m):
    a = rng.uniform(-0.3, 0.3, (m, 3))
    return ov.matrix_from_opk(a[:, 0], a[:, 1], a[:, 2])


def test_quaternion_roundtrip(rng):
    R = random_rotations(rng, 50)
    R[0] = np.diag([1.0, -1.0, -1.0])  # 180° about x: the w ≈ 0 branch
    q = g.wxyz_from_matrix(R)
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0)
    assert np.all(q[:, 0] >= 0)
    np.testing.assert_allclose(g.matrix_from_wxyz(q), R, atol=1e-12)


def test_frustum_apex_and_corners(rng):
    X0 = rng.uniform(-100, 100, (4, 3))
    R = random_rotations(rng, 4)
    c, fmt, depth = 152.0, (230.0, 230.0), 50.0
    C = g.frustum_corners(X0, R, c, fmt, depth)
    assert C.shape == (4, 5, 3)
    np.testing.assert_allclose(C[:, 0], X0)  # apex at the projection centre
    # each corner projects back to the image corner (x, y) = (±115, ±115) mm
    for k in range(4):
        xy = ov.project(C[k, 1:], X0[k], R[k], c)
        np.testing.assert_allclose(np.abs(xy), 115.0, atol=1e-9)
        # and lies at depth `depth` along the viewing direction (−z of the image frame)
        w = (C[k, 1:] - X0[k]) @ R[k]
        np.testing.assert_allclose(w[:, 2], -depth, atol=1e-9)
    seg = g.frustum_segments(C)
    assert seg.shape == (32, 2, 3)
    np.testing.assert_allclose(seg[:4, 0], np.repeat(X0[:1], 4, axis=0))


def test_viser_frustum_depth_matches_client_formula():
    # viser's client: y = tan(fov/2), x = y·aspect, z = 1, all divided by cbrt(x·y·z/3), × scale
    fov, aspect, scale = g.viser_frustum(152.0, (230.0, 180.0), 40.0)
    y = np.tan(fov / 2)
    x = y * aspect
    v = np.cbrt(x * y / 3)
    assert z_depth(scale[2], v) == pytest.approx(40.0)
    # the half-height over depth is the camera's: 90 mm / 152 mm
    assert (y / v * scale[1]) / (scale[2] / v) == pytest.approx(90.0 / 152.0)
    assert aspect == pytest.approx(230.0 / 180.0)


def z_depth(scale_z, volume_scale):
    return scale_z / volume_scale


def test_residual_offsets_put_the_observed_ray_through_the_offset_point(rng):
    n = 30
    X0 = np.array([0.0, 0.0, 1500.0])
    R = random_rotations(rng, 1)[0]
    P = np.column_stack([rng.uniform(-500, 500, (n, 2)), rng.uniform(-50, 50, n)])
    c = 152.0
    xy = ov.project(P, X0, R, c)
    e = rng.normal(0, 0.01, (n, 2))  # misclosure observed − computed, mm
    off = g.residual_offsets(
        P, np.broadcast_to(X0, (n, 3)), np.broadcast_to(R, (n, 3, 3)), np.full(n, c), e
    )
    # the offset point lies at the same depth and images exactly at the observed coordinates
    np.testing.assert_allclose(ov.project(P + off, X0, R, c), xy + e, atol=1e-9)
    np.testing.assert_allclose(((P + off - X0) @ R)[:, 2], ((P - X0) @ R)[:, 2], atol=1e-9)


def test_vector_segments_scale_with_exaggeration(rng):
    S, V = rng.normal(size=(5, 3)), rng.normal(size=(5, 3))
    for k in (1.0, 250.0):
        seg = g.vector_segments(S, V, k)
        np.testing.assert_allclose(seg[:, 0], S)
        np.testing.assert_allclose(seg[:, 1] - seg[:, 0], k * V)


def test_closest_points_of_rays():
    # two skew rays: along X at z = 0 and along Y at z = 2 → closest points (0,0,0), (0,0,2)
    P1, P2 = g.closest_points_of_rays([[5, 0, 0]], [[1, 0, 0]], [[0, 3, 2]], [[0, 1, 0]])
    np.testing.assert_allclose(P1, [[0, 0, 0]], atol=1e-12)
    np.testing.assert_allclose(P2, [[0, 0, 2]], atol=1e-12)
    # intersecting rays: no gap
    P1, P2 = g.closest_points_of_rays([[0, 0, 0]], [[1, 1, 0]], [[2, 0, 0]], [[-1, 1, 0]])
    np.testing.assert_allclose(P1, P2, atol=1e-12)
    np.testing.assert_allclose(P1, [[1, 1, 0]], atol=1e-12)


def test_polyline_segments_join_consecutive_members_of_each_group():
    P = np.arange(18, dtype=float).reshape(6, 3)
    seg = g.polyline_segments(P, [0, 0, 1, 1, 1, -1])
    assert seg.shape == (3, 2, 3)
    np.testing.assert_allclose(seg[0], P[[0, 1]])
    np.testing.assert_allclose(seg[1], P[[2, 3]])
    np.testing.assert_allclose(seg[2], P[[3, 4]])


def test_ellipsoid_mesh_vertices_lie_on_the_ellipsoid(rng):
    A = rng.normal(size=(3, 3, 3))
    S = A @ np.swapaxes(A, 1, 2) + 0.1 * np.eye(3)
    C = rng.normal(size=(3, 3))
    v, f = g.ellipsoid_mesh(C, S, scale=2.0, subdivisions=1)
    assert v.shape == (3 * 42, 3) and f.shape == (3 * 80, 3)
    assert f.max() == v.shape[0] - 1
    for k in range(3):
        d = v[k * 42 : (k + 1) * 42] - C[k]
        m2 = np.einsum("ni,ij,nj->n", d, np.linalg.inv(S[k]), d)
        np.testing.assert_allclose(m2, 4.0, rtol=1e-9)  # (X − c)ᵀ Σ⁻¹ (X − c) = scale²


def test_circles_and_spheres(rng):
    seg = g.circle_segments([[1.0, 2.0, 3.0]], [[0.0, 1.0, 1.0]], [5.0], n=40)
    assert seg.shape == (40, 2, 3)
    d = seg[:, 0] - [1.0, 2.0, 3.0]
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 5.0)
    np.testing.assert_allclose(d @ np.array([0.0, 1.0, 1.0]), 0.0, atol=1e-12)
    sph = g.sphere_wire_segments([[0.0, 0.0, 0.0]], [3.0], n_lat=3, n_lon=4, n=16)
    np.testing.assert_allclose(np.linalg.norm(sph.reshape(-1, 3), axis=1), 3.0)


def test_ramp_colours():
    col = g.ramp([0.0, 2.0, 4.0, 100.0, np.nan], 4.0)
    assert col.dtype == np.uint8 and col.shape == (5, 3)
    np.testing.assert_array_equal(col[0], [40, 160, 80])
    np.testing.assert_array_equal(col[1], [240, 170, 20])
    np.testing.assert_array_equal(col[2], [210, 30, 30])
    np.testing.assert_array_equal(col[3], col[2])  # saturates
    np.testing.assert_array_equal(col[4], [150, 150, 150])


def test_scene_frame_keeps_float32_precision():
    P = np.array([[450_000.0, 5_300_000.0, 400.0], [452_000.0, 5_301_500.0, 900.0]])
    f = g.SceneFrame.around(P)
    local = f.to_scene(P).astype(np.float32)
    np.testing.assert_allclose(local.astype(float) + f.origin, P, atol=1e-3)
    assert f.size == pytest.approx(2000.0)


def test_ray_segment_distances_match_a_dense_search(rng):
    o, d = rng.normal(size=3), rng.normal(size=3)
    seg = rng.normal(size=(40, 2, 3)) * 2.0
    seg[0] = [o - d, o - 3 * d]  # on the line behind the origin: distance |o - (o - d)|
    seg[1] = [o + 2 * d + [0.0, 0.0, 0.5], o + 4 * d + [0.0, 0.0, 0.5]]  # parallel, 0.5 off
    got = g.ray_segment_distances(o, d, seg)
    s = np.linspace(0.0, 12.0, 1201)[:, None]
    t = np.linspace(0.0, 1.0, 201)[:, None]
    P = o + s * d
    ref = np.array(
        [np.linalg.norm(P[:, None] - (a + t * (b - a))[None], axis=2).min() for a, b in seg]
    )
    assert np.all(got <= ref + 1e-12)  # never above a point actually reached
    np.testing.assert_allclose(got, ref, atol=0.01 * np.linalg.norm(d) + 0.02)
    assert got[0] == pytest.approx(np.linalg.norm(d), rel=1e-12)
    off = 0.5 * np.linalg.norm(np.cross(d, [0.0, 0.0, 1.0])) / np.linalg.norm(d)
    assert got[1] == pytest.approx(off, rel=1e-9)  # the offset across the line


def test_vertex_colours_decode_srgb():
    from orientviz.viewer.shapes import vertex_colours

    got = vertex_colours([[0, 10, 128], [255, 188, 40]])
    # sRGB → linear (IEC 61966-2-1): 10 → 0.0030 (linear part), 128 → 0.2159, 188 → 0.5029
    np.testing.assert_array_equal(got, [[0, 1, 55], [255, 128, 5]])
    assert got.dtype == np.uint8
