"""Design without measurements: predicted σ against Monte-Carlo and the adjusted block."""

from __future__ import annotations

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

import orientviz as ov
from orientviz.bundle import bundle_adjust
from orientviz.design import FlightDesign, assess_design, design_block, ellipsoids, set_control
from orientviz.errors import InputError

#: A small block: 2 strips of 6 images, standard points, perimeter control every 2 bases,
#: GNSS projection centres. Small enough for a Monte-Carlo of a few hundred adjustments.
SMALL = FlightDesign(
    strips=2, images_per_strip=6, control="perimeter", control_spacing=2, sigma_control=0.03,
    sigma_gnss=0.10,
)  # fmt: skip


@pytest.fixture(scope="module", autouse=True)
def _one_thread():
    with threadpool_limits(1, "blas"):
        yield


@pytest.fixture(scope="module")
def small():
    return assess_design(SMALL, law=False)


def _noisy(block, rng):
    """The design block with random errors of the size of its a-priori σ: image
    coordinates, given control coordinates, observed projection centres."""
    b = block.copy()
    o = b.observations
    o.xy = o.xy + rng.normal(0.0, 1.0, o.xy.shape) * o.sigma
    P = b.points
    g = np.isfinite(P.xyz_known)
    P.xyz_known[g] = P.xyz_known[g] + rng.normal(0.0, 1.0, int(g.sum())) * P.sigma[g]
    P.xyz[g] = P.xyz_known[g]
    im = b.images
    go = np.isfinite(im.X0_obs)
    im.X0_obs[go] = im.X0_obs[go] + rng.normal(0.0, 1.0, int(go.sum())) * im.X0_sigma[go]
    return b


def test_predicted_sigma_matches_a_monte_carlo_of_the_same_design(small):
    # N adjustments of the design block with random errors of the a-priori σ. Per sample
    # the mean over the points of e_jᵀ C_j⁻¹ e_j / 3 (C_j the predicted covariance) has
    # expectation 1 when the prediction is right; the samples are independent, so the
    # band is 4 standard errors of their mean, estimated from the samples themselves.
    q = small.quality
    block, truth_xyz = small.block, small.block.points.xyz
    truth_ext = small.result.exterior
    Cinv = np.linalg.inv(q.point_cov)
    N = 160
    rng = np.random.default_rng(2024)
    s_pts, s_z, s_st = [], [], []
    for _ in range(N):
        res = bundle_adjust(_noisy(block, rng), control="weighted", precision=False, max_iter=6)
        assert res.converged
        e = res.points - truth_xyz
        s_pts.append(np.mean(np.einsum("ni,nij,nj->n", e, Cinv, e)) / 3.0)
        s_z.append(np.mean((e[:, 2] / q.point_sigma[:, 2]) ** 2))
        de = res.exterior[:, :3] - truth_ext[:, :3]
        s_st.append(np.mean((de / q.station_sigma[:, :3]) ** 2))
    for name, s in (("points", s_pts), ("σ_Z", s_z), ("stations", s_st)):
        s = np.asarray(s)
        se = s.std(ddof=1) / np.sqrt(N)
        # the band is tight enough to see a 10 % error of the predicted variance (5 % in σ)
        assert 4 * se < 0.1, (name, se)
        assert abs(s.mean() - 1.0) < 4 * se, (name, s.mean(), se)


def test_a_wrong_prediction_leaves_the_band(small):
    # the same statistic with σ 10 % too large must fail (the test above can fail)
    q = small.quality
    rng = np.random.default_rng(7)
    s = []
    for _ in range(60):
        res = bundle_adjust(_noisy(small.block, rng), control="weighted", precision=False)
        e = res.points[:, 2] - small.block.points.xyz[:, 2]
        s.append(np.mean((e / (1.1 * q.point_sigma[:, 2])) ** 2))
    s = np.asarray(s)
    assert abs(s.mean() - 1.0) > 4 * s.std(ddof=1) / np.sqrt(s.size)


def test_design_equals_the_adjusted_simulated_block(small):
    # the simulated block of the same layout, with noise and start errors, adjusted: its
    # a-priori precision (σ0 = 1) at its own estimates equals the design's to first order
    sim = ov.simulate_block(
        SMALL.strips, SMALL.images_per_strip, rng=np.random.default_rng(SMALL.terrain_seed),
        relief=0.0, extra=None, control="perimeter", control_spacing=2, control_sigma=0.03,
        control_noise=0.03, flight_jitter=(0.0, 0.0, 0.0, 0.0),
    )  # fmt: skip
    np.testing.assert_allclose(sim.truth.points.xyz, small.block.points.xyz, atol=1e-9)
    b = sim.block.copy()
    b.images.X0_obs[:] = sim.truth.images.X0 + np.random.default_rng(3).normal(0, 0.1, (12, 3))
    b.images.X0_sigma[:] = 0.10
    res = bundle_adjust(b, control="weighted", precision=True)
    assert res.converged
    sig = np.sqrt(np.einsum("nii->ni", res.cofactor_groups["points"]))
    q = small.quality
    np.testing.assert_allclose(sig, q.point_sigma, rtol=2e-3)
    sst = np.sqrt(np.einsum("nii->ni", res.cofactor_groups["exterior"]))
    np.testing.assert_allclose(sst, q.station_sigma, rtol=2e-3)
    n = b.n_observations
    r = np.asarray(res.redundancy_numbers[: 2 * n]).reshape(n, 2)
    np.testing.assert_allclose(r, q.redundancy, atol=2e-3)


def test_reliability_and_ellipsoids_are_consistent(small):
    q = small.quality
    # MDB = δ0 σ / √r_min ≥ δ0 σ / √min(r_x, r_y) (r_min is the smaller eigenvalue)
    sig = small.block.observations.sigma[:, 0]
    fin = np.isfinite(q.mdb)
    assert fin.any()
    bound = 4.13 * sig[fin] / np.sqrt(q.redundancy[fin].min(axis=1))
    assert np.all(q.mdb[fin] >= bound * (1 - 1e-9))
    # ellipsoid: Σ a_i² = χ²₃(level) · trace(C)
    k = 7.814727903251178  # χ²₃ at 95 %
    np.testing.assert_allclose(
        (q.ellipsoid_axes**2).sum(1), k * np.trace(q.point_cov, axis1=1, axis2=2)
    )
    a, _ = ellipsoids(q.point_cov[:1], 0.5)
    assert np.all(a < q.ellipsoid_axes[:1])


def test_weak_spots_name_a_point_far_from_height_control():
    # control only at the corners of a long strip pair: the middle's heights are weak
    a = assess_design(FlightDesign(strips=2, images_per_strip=12, control="corners"), law=False)
    text = " ".join(a.quality.weak_spots)
    assert "σ_Z" in text and "base lengths from the nearest height control" in text
    s = a.quality.summary
    assert s["sigma_z_max"] >= 1.5 * s["sigma_z_median"]
    assert "cannot be tested" in text  # the corners' two-ray points


def test_more_control_never_worsens_sigma(small):
    block = small.block
    tie = np.flatnonzero(block.points.role == ov.TIE)
    b2 = set_control(block, int(tie[0]), (0.03, 0.03, 0.03))
    from orientviz.design import assess_block

    _, q2 = assess_block(b2, small.spec)
    assert np.all(q2.point_sigma <= small.quality.point_sigma * (1 + 1e-9))
    assert q2.point_sigma[tie[0], 2] < small.quality.point_sigma[tie[0], 2]


def test_design_rejects_fixed_control():
    with pytest.raises(InputError, match="sigma_control"):
        design_block(FlightDesign(sigma_control=0.0))


@pytest.mark.parametrize(
    "layout", [{}, {"control": "chains", "control_kind": "xy+z", "relief": 50.0, "extra": "grid"}]
)
def test_a_plan_whose_sigma_changed_has_the_block_made_anew(layout):
    """design_block keeps the planned geometry of recent layouts and sets the plan's σ: the
    block equals the one the simulator makes for that σ, and a caller changing its block
    does not change the next one."""
    from orientviz.design import _layout

    d1 = FlightDesign(strips=3, images_per_strip=6, **layout)
    d2 = d1.with_(sigma_image_mm=0.0123, sigma_control=0.077, sigma_gnss=0.5)
    b1, _ = design_block(d1)
    b1.points.xyz[:] = 0.0  # the caller's copy
    b1.observations.sigma[:] = 9.0
    b2, s2 = design_block(d2)  # from the kept geometry
    _layout._PLANNED.clear()
    ref, sref = design_block(d2)  # made anew by the simulator
    assert s2 == sref and s2["sigma_image_mm"] == 0.0123 and s2["control_sigma"] == 0.077
    for table in ("images", "points", "observations", "cameras"):
        for name, v in vars(getattr(ref, table)).items():
            if isinstance(v, np.ndarray) and v.dtype.kind in "fiub":
                np.testing.assert_array_equal(getattr(getattr(b2, table), name), v)
