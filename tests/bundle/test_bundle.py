"""Bundle block adjustment (orientviz.bundle)."""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.bundle.model import collinearity_block
from orientviz.camera import collinearity_jacobian
from orientviz.errors import DatumDefectError

GON = np.pi / 200


def _wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


@pytest.mark.parametrize("sequence", ["opk", "pok"])
def test_kernel_jacobian_matches_finite_differences(sequence):
    rng = np.random.default_rng(4)
    m, n = 3, 20
    X0 = np.column_stack([rng.uniform(0, 900, m), rng.uniform(0, 900, m), np.full(m, 1500.0)])
    ang = rng.normal(0, 0.05, (m, 3))
    ang[1, 2] += np.pi
    oi = rng.integers(0, m, n)
    xyz = np.column_stack(
        [rng.uniform(-400, 1300, n), rng.uniform(-400, 1300, n), rng.uniform(0, 150, n)]
    )
    c, z = np.full(m, 152.0), np.zeros(m)
    xy, Je, Jp = collinearity_block(X0, ang, c, z, z, oi, xyz, sequence)
    # the per-image kernel equals the reference per-ray implementation in orientviz.camera
    xy2, Je2, Jp2, _ = collinearity_jacobian(xyz, X0[oi], ang[oi], 152.0, 0, 0, sequence)
    np.testing.assert_allclose(xy, xy2, rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(Je, Je2, rtol=1e-12, atol=1e-12)
    # central differences: step 1e-3 m / 1e-7 rad, truncation error ~h² · f''' ≪ 1e-6 mm
    for k in range(6):
        h = 1e-3 if k < 3 else 1e-7
        Xp, Xm, ap, am = X0.copy(), X0.copy(), ang.copy(), ang.copy()
        if k < 3:
            Xp[:, k] += h
            Xm[:, k] -= h
        else:
            ap[:, k - 3] += h
            am[:, k - 3] -= h
        fd = (
            collinearity_block(Xp, ap, c, z, z, oi, xyz, sequence)[0]
            - collinearity_block(Xm, am, c, z, z, oi, xyz, sequence)[0]
        ) / (2 * h)
        np.testing.assert_allclose(Je[:, :, k], fd, rtol=1e-6, atol=1e-7)
    for k in range(3):
        d = np.zeros(3)
        d[k] = 1e-3
        fd = (
            collinearity_block(X0, ang, c, z, z, oi, xyz + d, sequence)[0]
            - collinearity_block(X0, ang, c, z, z, oi, xyz - d, sequence)[0]
        ) / 2e-3
        np.testing.assert_allclose(Jp[:, :, k], fd, rtol=1e-6, atol=1e-7)


def test_kernel_in_chunks_gives_the_numbers_of_one_chunk(monkeypatch):
    # 2·5 + 1 rays in chunks of 5: no chunk of a single ray (joined to the one before);
    # every operation is per ray, so the chunks change no number, mapped through M or not
    import orientviz.bundle.model._kernel as kernel

    rng = np.random.default_rng(5)
    m, n = 3, 11
    X0 = np.column_stack([rng.uniform(0, 900, m), rng.uniform(0, 900, m), np.full(m, 1500.0)])
    ang = rng.normal(0, 0.05, (m, 3))
    oi = rng.integers(0, m, n)
    xyz = np.column_stack([rng.uniform(0, 900, n), rng.uniform(0, 900, n), rng.uniform(0, 90, n)])
    c, z = np.full(m, 152.0), np.zeros(m)
    M = rng.standard_normal((n, 2, 2))

    def run():
        p = kernel.RayProjection(X0, ang, c, z, z, oi, xyz, "opk")
        return (
            p.xy,
            *kernel.ray_jacobians(p, ang, "opk"),
            *kernel.ray_jacobians(p, ang, "opk", M=M),
        )

    one = run()
    monkeypatch.setattr(kernel, "KERNEL_CHUNK", 5)
    assert kernel._chunks(n) == [(0, 5), (5, 11)]
    for a, b in zip(one, run()):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(one[3], M @ one[1], rtol=1e-14, atol=1e-12)


def test_noise_free_block_returns_truth():
    sim = ov.simulate_block(3, 6, rng=21, sigma_image_mm=0.0)
    res = ov.bundle_adjust(sim.block, precision=False)
    assert res.converged
    m = sim.block.n_images
    ext = res["exterior"].reshape(m, 6)
    # error-free observations: truth is the exact optimum; GN converges to rounding
    np.testing.assert_allclose(ext[:, :3], sim.truth.images.X0, atol=1e-6)
    np.testing.assert_allclose(_wrap(ext[:, 3:] - sim.truth.images.angles), 0, atol=1e-9)
    tie = sim.block.points.role == 0
    np.testing.assert_allclose(
        res["points"].reshape(-1, 3)[tie], sim.truth.points.xyz[tie], atol=1e-6
    )


def test_noisy_block_statistics_and_check_points():
    sim = ov.simulate_block(3, 8, rng=7, n_check=24)
    res = ov.bundle_adjust(sim.block)
    assert res.converged and res.iterations <= 8
    # σ̂0² ~ χ²_r / r: with r ≈ 3000 its standard deviation is √(2/r) ≈ 2.6 % → 4σ band
    assert abs(res.sigma0 - 1.0) < 4 * np.sqrt(0.5 / res.redundancy)
    assert np.isclose(np.nansum(res.redundancy_numbers), res.redundancy)
    w = res.normalized_residuals[: 2 * sim.block.n_observations]
    used = np.repeat(sim.block.points.role[sim.block.observations.point] != 2, 2)
    rn = res.redundancy_numbers[: 2 * sim.block.n_observations]
    assert np.all(np.isnan(w[~used]))
    # x of a two-ray point carries no redundancy (only the y-parallax is checked): w undefined
    assert np.all(np.isfinite(w[used & (rn > 1e-6)]))
    used &= rn > 1e-6
    # normalised residuals are N(0, 1): their RMS is 1 within a few % (n ≈ 6000)
    assert abs(np.sqrt(np.mean(w[used] ** 2)) - 1.0) < 0.06
    # check points: RMS differences against the truth are of the size of the predicted σ
    # of the (equally intersected) tie points; 24 points → ±15 % sampling error per axis
    rms = res.check_rms
    tie = sim.block.points.role == 0
    sig = np.sqrt(
        np.mean(res.std().reshape(-1)[res.groups["points"]].reshape(-1, 3)[tie] ** 2, axis=0)
    )
    ratio = rms / sig
    assert np.all((ratio > 0.5) & (ratio < 2.0)), ratio
    # check points did not enter the adjustment
    assert not res.used_obs[sim.block.points.role[sim.block.observations.point] == 2].any()


def test_history_replays_the_iterations():
    sim = ov.simulate_block(2, 5, rng=1)
    seen = []
    res = ov.bundle_adjust(sim.block, precision=False, callback=seen.append)
    assert len(res.history) == res.iterations + 1 == len(seen) + 1
    for a, b in zip(res.history[:-1], res.history[1:]):
        np.testing.assert_allclose(a.x + b.dx, b.x)
        assert b.cost <= a.cost
    np.testing.assert_array_equal(res.history[-1].x, res.x[: res.history[-1].x.size])


def test_weighted_control_differs_from_fixed_and_is_consistent():
    sim = ov.simulate_block(3, 6, rng=5, control_noise=0.05, control_sigma=0.05)
    fixed = ov.bundle_adjust(sim.block, control="fixed", precision=False)
    weighted = ov.bundle_adjust(sim.block, control="weighted")
    ctrl = sim.block.points.role == 1
    pts_f = fixed["points"].reshape(-1, 3)
    pts_w = weighted["points"].reshape(-1, 3)
    # fixed: control stays at its (noisy) given value; weighted: it moves
    np.testing.assert_array_equal(pts_f[ctrl], sim.block.points.xyz_known[ctrl])
    moved = np.abs(pts_w[ctrl] - sim.block.points.xyz_known[ctrl])
    assert moved.max() > 0.005
    # weighted control with σ equal to the simulated control noise: σ0 ≈ 1 (r ≈ 1500)
    assert abs(weighted.sigma0 - 1.0) < 0.12
    # a weighted control point adds 3 unknowns and 3 pseudo-observations: same redundancy
    assert weighted.redundancy == fixed.redundancy
    # pseudo-observation residuals are reported after the image residuals
    sl = weighted.obs_slices["control"]
    assert sl.stop - sl.start == 3 * int(ctrl.sum())


def test_datum_defect_is_named():
    sim = ov.simulate_block(2, 4, rng=2, control="none")
    with pytest.raises(DatumDefectError, match="7 datum parameter"):
        ov.bundle_adjust(sim.block)


def test_one_ray_points_and_disconnected_blocks_are_named():
    sim = ov.simulate_block(2, 4, rng=2)
    b = sim.block.copy()
    obs = b.observations
    tie = np.flatnonzero(b.points.role[obs.point] == 0)
    pt = obs.point[tie[0]]
    keep = (obs.point != pt) | (np.arange(len(obs)) == tie[0])
    from orientviz.block import Observations

    b.observations = Observations(obs.image[keep], obs.point[keep], obs.xy[keep], obs.sigma[keep])
    with pytest.raises(ov.NotDeterminableError, match=b.points.ids[pt]):
        ov.bundle_adjust(b)
    # cut a strip of 7 images between image 1 and 2: drop every point seen on both sides
    sim = ov.simulate_block(1, 7, rng=3)
    b = sim.block.copy()
    obs = b.observations
    left = np.isin(obs.image, [0, 1])
    seen_l = np.bincount(obs.point[left], minlength=b.n_points) > 0
    seen_r = np.bincount(obs.point[~left], minlength=b.n_points) > 0
    keep = ~(seen_l & seen_r)[obs.point]
    b.observations = Observations(obs.image[keep], obs.point[keep], obs.xy[keep], obs.sigma[keep])
    with pytest.raises(ov.NotDeterminableError, match="disconnected") as info:
        ov.bundle_adjust(b)
    assert b.images.ids[1] in str(info.value)


class Affinity:
    """Affinity + shear, 1 unit = 1 µm at x = 100 mm (a minimal additional-parameter set)."""

    name = "affinity"
    names = ["a1", "a2"]

    def design(self, xy):
        A = np.zeros((xy.shape[0], 2, 2))
        A[:, 0, 0] = 1e-5 * xy[:, 0]
        A[:, 1, 0] = -1e-5 * xy[:, 1]
        A[:, 1, 1] = 1e-5 * xy[:, 0]
        return A


def test_self_calibration_recovers_a_simulated_affinity():
    true = np.array([8.0, -5.0])  # µm at 100 mm: the 10 µm class of Ackermann's systematic errors
    ap = Affinity()

    def systematic(xy, img):
        # the model is x_obs + v = f + A a, so the observations carry +A a
        return np.einsum("nij,j->ni", ap.design(xy), true)

    sim = ov.simulate_block(3, 6, rng=9, systematic=systematic)
    plain = ov.bundle_adjust(sim.block, precision=False)
    cal = ov.bundle_adjust(sim.block, additional=ap, ap_sigma=100.0)
    est = cal["additional"]
    sd = cal.std()[cal.groups["additional"]]
    assert np.all(np.abs(est - true) < 4 * sd), (est, sd)
    assert cal.sigma0 < plain.sigma0
    assert abs(cal.sigma0 - 1.0) < 0.1
    # one group per strip: three sets of parameters
    grp = sim.block.images.strip
    per_strip = ov.bundle_adjust(
        sim.block, additional=ap, ap_group=grp, ap_sigma=100.0, precision=False
    )
    assert per_strip["additional"].shape == (6,)


def test_a_sets_name_stands_for_the_set_and_anything_else_is_named_in_one_line():
    from orientviz.bundle import ap_set
    from orientviz.errors import InputError

    sim = ov.simulate_block(2, 5, rng=4)
    by_name = ov.bundle_adjust(sim.block, additional="ebner12", ap_sigma=100.0, precision=False)
    by_set = ov.bundle_adjust(
        sim.block, additional=ap_set("ebner12"), ap_sigma=100.0, precision=False
    )
    assert by_name["additional"].shape == (12,)
    np.testing.assert_array_equal(by_name.x, by_set.x)
    with pytest.raises(InputError, match="unknown additional-parameter set 'ebner13'"):
        ov.bundle_adjust(sim.block, additional="ebner13")
    with pytest.raises(InputError, match=r"additional: expected .* got int"):
        ov.bundle_adjust(sim.block, additional=12)


def test_approximate_values_from_scratch_reach_the_same_optimum():
    from orientviz.approximate import approximate_values

    sim = ov.simulate_block(3, 6, rng=13)
    ref = ov.bundle_adjust(sim.block, precision=False)
    scrambled = sim.block.copy()
    scrambled.images.X0[:] = 0.0  # nothing of the stored approximations is used
    scrambled.images.angles[:] = 0.0
    scrambled.points.xyz[:] = 0.0
    approx = approximate_values(scrambled)
    # the chain of resections/intersections lands within metres and centigon of the truth
    assert np.abs(approx.images.X0 - sim.truth.images.X0).max() < 10.0
    assert np.abs(_wrap(approx.images.angles - sim.truth.images.angles)).max() < 0.5 * GON
    res = ov.bundle_adjust(approx, precision=False)
    assert res.converged
    # same least-squares optimum: agreement far below the point precision (cm)
    np.testing.assert_allclose(res["points"], ref["points"], atol=1e-4)
    assert np.isclose(res.sigma0, ref.sigma0, rtol=1e-8)


def test_poor_start_reports_non_convergence_not_a_defect():
    sim = ov.simulate_block(2, 6, rng=4, start_error=(300.0, 30 * GON, 300.0))
    try:
        res = ov.bundle_adjust(sim.block, precision=False, max_iter=15)
    except ov.NotDeterminableError as exc:  # pragma: no cover - must not be blamed on geometry
        pytest.fail(f"poor approximations reported as a defect: {exc}")
    if res.converged:  # converging is fine too; then it must be the true optimum
        good = ov.bundle_adjust(sim.block.with_(images=sim.truth.images), precision=False)
        assert np.isclose(res.sigma0, good.sigma0, rtol=1e-6)
    else:
        assert "approximate" in res.reason or "iterations" in res.reason


def test_observed_projection_centres_give_the_datum():
    # GNSS-like projection centres (σ = 0.1 m) and no control at all
    sim = ov.simulate_block(3, 6, rng=17, control="none")
    b = sim.block.copy()
    rng = np.random.default_rng(3)
    b.images.X0_obs = sim.truth.images.X0 + rng.normal(0, 0.1, b.images.X0.shape)
    b.images.X0_sigma = np.full_like(b.images.X0, 0.1)
    res = ov.bundle_adjust(b)
    assert res.converged
    # r ≈ 1500: σ̂0 within ±4·√(1/(2r)) ≈ ±7 % of 1
    assert abs(res.sigma0 - 1.0) < 0.08
    sl = res.obs_slices["X0_obs"]
    assert sl.stop - sl.start == 3 * b.n_images
    # the centres are pulled to the truth to about their σ, not beyond
    ext = res["exterior"].reshape(-1, 6)
    err = np.sqrt(np.mean((ext[:, :3] - sim.truth.images.X0) ** 2))
    assert err < 0.1
    # without the observed centres the same block has no datum
    with pytest.raises(DatumDefectError):
        ov.bundle_adjust(sim.block)


def test_reduced_solvers_reach_the_same_solution():
    sim = ov.simulate_block(2, 5, rng=8)
    ref = ov.bundle_adjust(sim.block, precision=False, solver="banded")
    for solver in ("sparse", "dense"):
        res = ov.bundle_adjust(sim.block, precision=False, solver=solver)
        assert res.iterations == ref.iterations
        # the same linear systems solved by different factorisations: rounding only
        np.testing.assert_allclose(res.x, ref.x, rtol=0, atol=1e-7)


def test_height_only_control_points_are_held_in_height():
    sim = ov.simulate_block(3, 6, rng=23, control="chains", control_kind="xyz")
    b = sim.block.copy()
    ctrl = np.flatnonzero(b.points.role == 1)
    inner = ctrl[len(ctrl) // 2 :]  # make half of the control height-only
    b.points.xyz_known[inner, :2] = np.nan
    res = ov.bundle_adjust(b, precision=False)
    pts = res["points"].reshape(-1, 3)
    # heights stay at the given value (σ 1e-6 m pseudo-observation), X/Y are estimated
    np.testing.assert_allclose(pts[inner, 2], b.points.xyz_known[inner, 2], atol=1e-5)
    assert np.abs(pts[inner, :2] - sim.truth.points.xyz[inner, :2]).max() < 0.5


def _z_only_centres(block, truth, sigma=0.1):
    """Statoscope-like observations: Z0 observed, X0/Y0 not (NaN value and σ)."""
    b = block.copy()
    b.images.X0_obs = np.full_like(b.images.X0, np.nan)
    b.images.X0_sigma = np.full_like(b.images.X0, np.nan)
    b.images.X0_obs[:, 2] = truth.images.X0[:, 2]
    b.images.X0_sigma[:, 2] = sigma
    return b


def test_height_only_datum_is_diagnosed_not_a_linalg_error():
    from orientviz.bundle.problem import datum_defect, point_setup

    sim = ov.simulate_block(3, 6, rng=17, control="none")
    b = _z_only_centres(sim.block, sim.truth)
    # heights from the centres fix shift Z and both tilts; planimetry stays free
    with pytest.raises(DatumDefectError, match="4 datum") as info:
        ov.bundle_adjust(b)
    assert info.value.parameters == [
        "datum: shift X", "datum: shift Y", "datum: rotation κ", "datum: scale",
    ]  # fmt: skip
    # height-only control points whose approximate X, Y are unknown too
    sim2 = ov.simulate_block(3, 6, rng=17, control="perimeter")
    b2 = sim2.block.copy()
    ctrl = np.flatnonzero(b2.points.role == 1)
    b2.points.xyz_known[ctrl, :2] = np.nan
    b2.points.xyz[ctrl[:3], :2] = np.nan
    free, missing = datum_defect(b2, point_setup(b2, "fixed"))
    assert free == 4 and "planimetric" in missing


def test_planimetric_control_and_z_only_centres_give_the_datum():
    sim = ov.simulate_block(3, 6, rng=17, control="perimeter")
    b = _z_only_centres(sim.block, sim.truth)
    ctrl = np.flatnonzero(b.points.role == 1)
    b.points.xyz_known[ctrl, 2] = np.nan  # control in X, Y only; heights from the centres
    res = ov.bundle_adjust(b, precision=False)
    assert res.converged
    assert abs(res.sigma0 - 1.0) < 0.1


def test_result_names_read_like_the_list_of_parameter_names():
    sim = ov.simulate_block(2, 5, rng=3)
    res = ov.bundle_adjust(sim.block, precision=False)
    b = sim.block
    want = [f"{i}.{n}" for i in b.images.ids for n in ("X0", "Y0", "Z0", "omega", "phi", "kappa")]
    want += [f"{i}.{c}" for i in b.points.ids for c in ("X", "Y", "Z")]
    assert len(res.names) == len(want) == res.x.size
    assert res.names == want and list(res.names) == want
    assert res.names[: 6 * b.n_images] == want[: 6 * b.n_images]
    name = f"{b.points.ids[2]}.Y"
    assert name in res.names and res.index(name) == want.index(name)
    assert res[name] == res.x[want.index(name)]


def test_the_jacobians_of_a_kept_projection_are_those_of_its_state():
    from orientviz.bundle.problem import BundleProblem, BundleState, point_setup

    sim = ov.simulate_block(2, 5, rng=8)
    b = sim.block
    prob = BundleProblem(b, point_setup(b, "fixed"))
    z = np.zeros(0)
    st = BundleState(b.images.X0.copy(), b.images.angles.copy(), b.points.xyz.copy(), z, z)
    moved = BundleState(st.X0 + 0.5, st.angles + 1e-3, st.xyz, z, z)
    for local in (False, True):
        rw, Je, Jp = prob.residuals(st, jac=True, local=local)
        rw1, none, _ = prob.residuals(st, jac=False, keep=True)
        assert none is None
        np.testing.assert_array_equal(rw1, rw)
        for a, b_ in zip(prob.residuals(st, jac=True, local=local), (rw, Je, Jp)):
            np.testing.assert_array_equal(a, b_)
        # a projection kept at one state never serves another
        prob.residuals(st, jac=False, keep=True)
        want = prob.residuals(moved, jac=True, local=local)
        assert not np.array_equal(want[0], rw)
        prob.residuals(st, jac=False, keep=True)
        for a, b_ in zip(prob.residuals(moved, jac=True, local=local), want):
            np.testing.assert_array_equal(a, b_)


def test_image_residuals_are_those_of_the_adjusted_values():
    from orientviz.bundle.model import project_block

    sim = ov.simulate_block(3, 8, rng=7, n_check=24)
    b = sim.block
    res = ov.bundle_adjust(b, precision=False)
    obs, cam = b.observations, b.images.camera
    ext = res["exterior"].reshape(-1, 6)
    f = project_block(
        ext[:, :3], ext[:, 3:], b.cameras.c[cam], b.cameras.x0[cam], b.cameras.y0[cam],
        obs.image, res.points[obs.point], b.sequence,
    )  # fmt: skip
    n = b.n_observations
    np.testing.assert_allclose(res.residuals[: 2 * n], (f - obs.xy).reshape(-1), rtol=0, atol=1e-12)
    assert not res.used_obs.all()  # the check points' rays are among them
