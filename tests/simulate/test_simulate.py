"""Tests of the block simulator (orientviz.simulate)."""

import math

import numpy as np
import pytest

import orientviz as ov
from orientviz.block import CHECK, CONTROL, block_layout


def small(**kw):
    kw.setdefault("rng", np.random.default_rng(7))
    return ov.simulate_block(3, 8, **kw)


def test_deterministic_for_a_seed():
    a, b = small(rng=np.random.default_rng(3)), small(rng=np.random.default_rng(3))
    np.testing.assert_array_equal(a.block.observations.xy, b.block.observations.xy)
    np.testing.assert_array_equal(a.block.images.X0, b.block.images.X0)
    c = small(rng=np.random.default_rng(4))
    assert not np.array_equal(a.truth.points.xyz[:5], c.truth.points.xyz[:5])


def test_noise_does_not_move_the_geometry():
    a = small(rng=np.random.default_rng(3))
    b = small(rng=np.random.default_rng(3), sigma_image_mm=0.010)
    np.testing.assert_array_equal(a.truth.points.xyz, b.truth.points.xyz)
    np.testing.assert_array_equal(a.truth.images.X0, b.truth.images.X0)


def test_default_geometry_matches_the_bench_blocks():
    s = small()
    assert s.spec["flying_height_m"] == pytest.approx(1520.0)
    assert s.spec["base_m"] == pytest.approx(920.0)
    assert s.spec["strip_spacing_m"] == pytest.approx(1840.0)
    # strips alternate: kappa ~ 0 for strip 0, ~ 200 gon for strip 1 (flight jitter 1 gon)
    kap = s.truth.images.angles[:, 2]
    st = s.truth.images.strip
    assert np.all(np.abs(kap[st == 0]) < 0.1)
    assert np.all(np.abs(np.abs(kap[st == 1]) - math.pi) < 0.1)
    # about as many points per image as the bench's 30 mm grid gives (~50) plus 9 standard
    ppi = s.block.points_per_image()
    assert 40 < ppi.mean() < 80


def test_truth_is_error_free_and_noise_has_the_given_sigma():
    s = ov.simulate_block(6, 12, rng=np.random.default_rng(1))
    np.testing.assert_array_equal(s.truth.residuals(), 0.0)
    e = s.block.observations.xy - s.truth.observations.xy
    n = e.size
    # relative standard error of an RMS from n samples is 1/sqrt(2n) ~ 0.4 %; allow 4 of them
    assert np.sqrt(np.mean(e**2)) == pytest.approx(0.005, rel=4 / math.sqrt(2 * n))
    d = s.block.images.X0 - s.truth.images.X0
    assert 3.0 < np.sqrt(np.mean(d**2)) < 7.0  # start error σ = 5 m, 216 samples


def test_every_point_has_two_rays_and_every_model_six_standard_points():
    s = ov.simulate_block(3, 8, rng=np.random.default_rng(2), extra=None)
    b = s.block
    assert b.rays_per_point().min() >= 2
    obs = b.observations
    for left, right in s.layout.models:
        common = np.intersect1d(obs.point[obs.image == left], obs.point[obs.image == right])
        assert common.size >= 6
    assert s.layout.n_models == 3 * 7


@pytest.mark.parametrize(
    ("control", "kw", "expected"),
    [("corners", {}, 4), ("perimeter", {"control_spacing": 4}, 8), ("none", {}, 0)],
)
def test_control_layouts(control, kw, expected):
    s = ov.simulate_block(3, 8, rng=np.random.default_rng(2), extra=None, control=control, **kw)
    ctrl = s.block.points.role == CONTROL
    assert ctrl.sum() == expected
    np.testing.assert_array_equal(s.block.points.xyz[ctrl], s.truth.points.xyz[ctrl])


def test_chains_xy_plus_z():
    s = ov.simulate_block(
        3, 9, rng=np.random.default_rng(2), extra=None, control="chains", chain_spacing=4,
        control_spacing=3, control_kind="xy+z",
    )  # fmt: skip
    p = s.block.points
    ctrl = p.role == CONTROL
    given = ~np.isnan(p.xyz_known[ctrl])
    # chains at columns 0, 4, 8: 3 chains x 7 rows carry heights
    assert np.sum(given[:, 2]) == 3 * 7
    # perimeter points at columns 3 and 6 (between the chains) are planimetric only
    assert np.any(given[:, 0] & ~given[:, 2])
    # interior chain points are height only
    assert np.any(~given[:, 0] & given[:, 2])
    assert np.all(p.sigma[ctrl][given] == 0.0)


def test_check_points_are_given_but_not_control():
    s = ov.simulate_block(3, 8, rng=np.random.default_rng(2), n_check=5)
    chk = s.block.points.role == CHECK
    assert chk.sum() == 5
    np.testing.assert_array_equal(s.block.points.xyz_known[chk], s.truth.points.xyz[chk])


def test_gross_and_systematic_hooks_are_recorded():
    def radial(xy, image):
        return 1e-4 * xy * (np.sum(xy**2, axis=1, keepdims=True) / 100.0**2)

    s = ov.simulate_block(
        3, 8, rng=np.random.default_rng(5), sigma_image_mm=0.0, gross={"count": 7, "size_mm": 0.1},
        systematic=radial,
    )  # fmt: skip
    g = s.info["gross"]
    assert g["index"].size == 7
    d = s.block.observations.xy - s.truth.observations.xy - s.info["systematic"]
    np.testing.assert_allclose(d[g["index"]], g["error_mm"], atol=1e-12)
    np.testing.assert_allclose(np.hypot(*g["error_mm"].T), 0.1)
    others = np.setdiff1d(np.arange(d.shape[0]), g["index"])
    np.testing.assert_allclose(d[others], 0.0, atol=1e-12)


def test_layout_footprints_and_superwide_camera():
    s = ov.simulate_block(
        2,
        5,
        rng=np.random.default_rng(1),
        camera="superwide",
        relief=0.0,
        flight_jitter=(0, 0, 0, 0),
    )
    lay = block_layout(s.truth)
    width = np.ptp(lay.footprints[:, :, 0], axis=1)
    # exactly vertical images over flat ground: footprint = 0.23 m * scale
    np.testing.assert_allclose(width, 2300.0, rtol=1e-12)
    assert s.spec["flying_height_m"] == pytest.approx(880.0)
    assert [len(x) for x in lay.strips] == [5, 5]


@pytest.mark.parametrize(
    "kw",
    [
        {"camera": "fisheye"},
        {"control": "everywhere"},
        {"forward_overlap": 0.3},
        {"control_kind": "z"},
        {"gross": {"count": 10**9}},
        {"rng": None},
    ],
)
def test_bad_input_gives_one_clear_line(kw):
    kw.setdefault("rng", np.random.default_rng(0))
    with pytest.raises(ov.InputError) as exc:
        ov.simulate_block(2, 4, **kw)
    assert "\n" not in str(exc.value)


def test_block_take_keeps_rows_and_renumbers_the_observations():
    b = small().block
    images, points = np.array([1, 2, 5]), np.flatnonzero(np.arange(b.n_points) % 2 == 0)
    o = b.observations
    obs = np.flatnonzero(np.isin(o.image, images) & np.isin(o.point, points))
    sub = b.take(images, points, obs)
    assert sub.images.ids == [b.images.ids[i] for i in images]
    assert sub.points.ids == [b.points.ids[i] for i in points]
    # every kept observation still names the same image and point, by id
    np.testing.assert_array_equal(
        [sub.images.ids[i] for i in sub.observations.image], [b.images.ids[i] for i in o.image[obs]]
    )
    np.testing.assert_array_equal(
        [sub.points.ids[p] for p in sub.observations.point], [b.points.ids[p] for p in o.point[obs]]
    )
    np.testing.assert_array_equal(sub.observations.xy, o.xy[obs])
    sub.points.xyz[0] += 1.0  # a copy: the whole block is untouched
    assert not np.array_equal(sub.points.xyz[0], b.points.xyz[points[0]])


def test_flat_terrain_is_its_base_height_and_draws_the_hills_alike():
    """relief 0: every height is the base height (no hills summed), and the random
    stream is used as with relief (the rest of a simulation stays the same)."""
    from orientviz.simulate._terrain import Terrain

    ext = (0.0, 5000.0, 0.0, 3000.0)
    r0, r1 = np.random.default_rng(4), np.random.default_rng(4)
    flat, hilly = Terrain(r0, ext, 0.0, 250.0), Terrain(r1, ext, 80.0, 250.0)
    x = np.linspace(0.0, 5000.0, 7)
    assert np.array_equal(flat(x, x[::-1]), np.full(7, 250.0))
    assert np.ptp(hilly(x, x[::-1])) > 1.0
    assert r0.random() == r1.random()
