"""Auxiliary data (GNSS, statoscope, APR) as joint observations with strip offsets."""

import numpy as np
import pytest

import orientviz as ov
from orientviz.block import CONTROL
from orientviz.bundle import adjust_with_auxiliary
from orientviz.bundle.problem import BundleAuxiliary, auxiliary_rows
from orientviz.simulate import check_errors, height_control_at_ends, simulate_auxiliary


@pytest.fixture(scope="module")
def case():
    """4 × 16 block: planimetric perimeter control; height control in chains every 2
    bases ("full"), or only in the two end chains ("ends"); statoscope and APR data."""
    sim = ov.simulate_block(
        4, 16, rng=np.random.default_rng(8), control="chains", control_kind="xy+z",
        chain_spacing=2, n_check=30,
    )  # fmt: skip
    full = sim.block
    thin = height_control_at_ends(full)
    kept = np.isfinite(thin.points.xyz_known[:, 2]) & (thin.points.role == CONTROL)
    assert 0 < kept.sum() < 0.5 * np.sum(np.isfinite(full.points.xyz_known[:, 2]))
    rng = np.random.default_rng(1)
    st = simulate_auxiliary(
        sim, "statoscope", rng=rng, sigma=0.3, offset_sigma=20.0, drift_sigma=2.0
    )
    apr = simulate_auxiliary(sim, "apr", rng=rng, sigma=0.5, offset_sigma=20.0)
    return sim, full, thin, st, apr


def _check_rms(sim, xyz):
    return check_errors(sim, xyz)


def test_rows_and_jacobians_match_finite_differences(case):
    sim, full, thin, st, apr = case
    g = simulate_auxiliary(sim, "gnss", rng=np.random.default_rng(4), drift_sigma=0.2)
    for aux in ([g, apr], [st]):
        rows = auxiliary_rows(aux, thin)
        rng = np.random.default_rng(0)
        vals = rng.normal(size=rows.n)
        gl = rng.normal(size=rows.n_global)
        J = rows.jacobian_global()
        v0 = rows.residuals(vals, gl)
        h = 1e-4
        for k in range(rows.n_global):
            e = np.zeros(rows.n_global)
            e[k] = h
            np.testing.assert_allclose((rows.residuals(vals, gl + e) - v0) / h, J[:, k], atol=1e-8)
        np.testing.assert_allclose(rows.residuals(vals + h, gl) - v0, h, atol=1e-12)
        # the bundle's view: derivatives by X0 and the point coordinates
        pt_col = np.arange(thin.n_points)
        ba = BundleAuxiliary(rows, pt_col)
        X0 = sim.truth.images.X0.copy()
        xyz = sim.truth.points.xyz.copy()
        v = ba.residuals(X0, xyz, gl)
        i = int(np.flatnonzero(rows.on_image)[0]) if rows.on_image.any() else None
        if i is not None:
            X0b = X0.copy()
            X0b[rows.target[i], rows.coord[i]] += h
            dv = (ba.residuals(X0b, xyz, gl) - v) / h
            assert dv[i] == pytest.approx(1.0) and np.count_nonzero(np.abs(dv) > 1e-9) >= 1
        pts = np.flatnonzero(~rows.on_image)
        if pts.size:
            xyzb = xyz.copy()
            xyzb[rows.target[pts[0]], 2] += h
            dv = (ba.residuals(X0, xyzb, gl) - v) / h
            assert dv[pts[0]] == pytest.approx(1.0)


def test_statoscope_and_apr_replace_height_chains_in_independent_models(case):
    sim, full, thin, st, apr = case
    z_full = _check_rms(sim, ov.independent_models(full).points)[1]
    z_ends = _check_rms(sim, ov.independent_models(thin).points)[1]
    res = ov.independent_models(thin, auxiliary=[st, apr])
    assert res.converged
    z_aux = _check_rms(sim, res.points)[1]
    # Ackermann §19: the auxiliary data take over most of the interior height control
    assert z_full < z_ends and z_aux < 0.6 * z_ends
    # the statoscope offsets come back (4 strips, 20 m σ), to a few dm
    est = res.auxiliary.offsets["statoscope"][:, 0, 0]
    np.testing.assert_allclose(est, st.truth["offset"][:, 0], atol=1.0)
    assert res.auxiliary.sigma["statoscope"].shape == (4, 1, 2)
    assert res.auxiliary.residuals.size == st.index.size + apr.index.size


def test_gnss_alone_gives_the_datum_and_offsets_without_control_do_not(case):
    sim, full, thin, st, apr = case
    free = full.copy()
    free.points.role[free.points.role == CONTROL] = 0
    free.points.xyz_known[:] = np.nan
    rng = np.random.default_rng(5)
    g = simulate_auxiliary(
        sim, "gnss", rng=rng, sigma=0.1, offset_sigma=0.0, estimate_offsets=False
    )
    res = ov.independent_models(free, auxiliary=[g])
    assert res.converged
    xy, z = _check_rms(sim, res.points)
    assert xy < 0.15 and z < 0.2
    g2 = simulate_auxiliary(sim, "gnss", rng=rng, sigma=0.1, offset_sigma=0.5)
    with pytest.raises(ov.NotDeterminableError):
        ov.independent_models(free, auxiliary=[g2])


def test_joint_bundle_equals_the_alternation_and_is_one_adjustment(case):
    sim, full, thin, st, apr = case
    joint = ov.bundle_adjust(thin, control="weighted", auxiliary=[st, apr])
    alt = adjust_with_auxiliary(thin, [st, apr], tol=0.005)
    assert joint.converged and alt.converged and alt.rounds > 1
    for kind in ("statoscope", "apr"):
        np.testing.assert_allclose(joint.auxiliary.offsets[kind], alt.offsets[kind], atol=0.03)
    d = joint.points - alt.adjustment.points
    assert np.nanmax(np.abs(d)) < 0.05
    sig = joint.auxiliary.sigma["statoscope"]
    assert np.all(np.isfinite(sig)) and np.all(sig > 0)


def test_bad_auxiliary_input(case):
    sim, full, thin, st, apr = case
    g = simulate_auxiliary(sim, "gnss", rng=np.random.default_rng(2))
    with pytest.raises(ov.InputError, match="both observe Z0"):
        ov.independent_models(thin, auxiliary=[st, g])
    with pytest.raises(ov.InputError, match="at most one each"):
        auxiliary_rows([st, st], thin)
    with pytest.raises(ov.InputError, match="rigorous"):
        ov.independent_models(thin, auxiliary=[st], method="pat-m")
