"""Model deformation parameters (self-calibration) in the independent-model adjustment."""

import dataclasses

import numpy as np
import pytest

import orientviz as ov
from orientviz.rotation import matrix_from_rotvec
from orientviz.simulate import systematic as sy
from orientviz.stereo_models import (
    MODEL_SETS,
    TERMS,
    deformed,
    form_models,
    joint_setup,
    model_ap_set,
    model_rows,
    similarity_columns,
    tie_setup,
)

W3 = np.array([1.0, 1.0, 0.25])


@pytest.fixture(scope="module")
def small():
    return ov.simulate_block(2, 6, rng=np.random.default_rng(3), control="chains")


def test_fields_are_orthogonal_to_the_similarity(small):
    ms = form_models(small.block)
    su = tie_setup(small.block, ms)
    ground = su.row_point < su.tie_points.size
    fld = model_ap_set("all").fit(su.m, su.row_model, ground, W3, ms.n_models)
    A = fld.evaluate(su.m, su.row_model, ground)
    S = similarity_columns(su.m)
    sw = np.sqrt(W3)[None, :, None]
    for j in range(ms.n_models):
        rows = np.flatnonzero((su.row_model == j) & ground)
        Sj = (S[rows] * sw).reshape(-1, 7)
        Aj = (A[rows] * sw).reshape(-1, len(TERMS))
        # scaled so that a full correlation would read 1
        c = (Sj.T @ Aj) / np.outer(np.linalg.norm(Sj, axis=0), np.linalg.norm(Aj, axis=0) + 1e-30)
        assert np.abs(c).max() < 1e-8
        assert np.all(A[(su.row_model == j) & ~ground] == 0.0)  # centres not deformed
    # a non-trivial field survives the projection (the twist is no similarity)
    assert np.linalg.norm(A[:, 2, TERMS.index("twist")]) > 1e-3


def test_jacobians_match_finite_differences(small):
    ms = form_models(small.block)
    su = tie_setup(small.block, ms)
    w_c = np.array([1.0, 1.0, 0.25])
    js = joint_setup(small.block, ms, su, w_c, model_ap_set("classical"), "strip", 100.0, None)
    rng = np.random.default_rng(0)
    n = ms.n_models
    lam = 1 + 1e-3 * rng.standard_normal(n)
    R = ms.start_rotation @ matrix_from_rotvec(1e-3 * rng.standard_normal((n, 3)))
    T = ms.start_translation + rng.standard_normal((n, 3))
    su.init_points(lam, R, T)
    p = 50.0 * rng.standard_normal(js.n_def)
    r, J, Jp = model_rows(su, js, lam, R, T, p)
    j = su.row_model
    h = 1e-6
    for k in range(3):  # rotation-vector increments on the right of R
        d = np.zeros((n, 3))
        d[:, k] = h
        r2 = model_rows(su, js, lam, R @ matrix_from_rotvec(d), T, p)[0]
        np.testing.assert_allclose((r2 - r) / h, J[:, :, k], atol=2e-3 * np.abs(J).max())
    r2 = model_rows(su, js, lam + h, R, T, p)[0]
    np.testing.assert_allclose((r2 - r) / h, J[:, :, 3], rtol=1e-5, atol=1e-5)
    for k in range(js.q):
        dp = np.zeros_like(p)
        g = js.group[j]
        dp[np.arange(js.n_groups) * js.q + k] = 1.0  # linear: exact with step 1
        r2 = model_rows(su, js, lam, R, T, p + dp)[0]
        np.testing.assert_allclose(r2 - r, Jp[:, :, k], atol=1e-12)
        assert g.max() == js.n_groups - 1


def test_known_model_deformation_is_recovered_noise_free():
    """Deform the models by a known block-wide field; the adjustment finds it again."""
    sim = ov.simulate_block(3, 8, rng=np.random.default_rng(11), sigma_image_mm=0.0)
    ms = form_models(sim.block)
    su = tie_setup(sim.block, ms)
    ground = su.row_point < su.tie_points.size
    spec = model_ap_set("classical")
    fld = spec.fit(su.m, su.row_model, ground, W3, ms.n_models)
    p_true = np.array([40.0, -25.0, 30.0, 20.0, -60.0, 35.0, -45.0])  # mm at a corner
    A = fld.evaluate(ms.xyz, ms.point_model)
    ms_d = dataclasses.replace(ms, xyz=ms.xyz + A @ p_true)
    plain = ov.independent_models(sim.block, models=ms_d)
    res = ov.independent_models(
        sim.block, models=ms_d, deformation=spec, deformation_group="block", deformation_sigma=None
    )
    assert res.converged
    # the adjustment fits the fields on the *deformed* models, which shifts their
    # normalisation and projection slightly: the parameters come back to 1 % of the
    # largest one, the residuals and point errors shrink by well over an order
    np.testing.assert_allclose(res.deformation.values[0], p_true, atol=0.6)
    assert res.sigma0 < 0.02 * plain.sigma0
    err = np.nanmax(np.abs(res.points - sim.truth.points.xyz))
    assert np.nanmax(np.abs(plain.points - sim.truth.points.xyz)) > 10 * err


@pytest.mark.parametrize("error", ["twist", "bend"])
def test_model_self_calibration_lowers_sigma0_and_check_errors(error):
    make = {"twist": sy.model_twist, "bend": sy.model_bending}[error]
    sim = ov.simulate_block(
        4, 12, rng=np.random.default_rng(5), control="chains", control_spacing=2, n_check=40,
        systematic=make(15.0), sigma_image_mm=0.003,
    )  # fmt: skip
    chk = sim.block.points.role == 2

    def rms(r):
        d = r.points[chk] - sim.truth.points.xyz[chk]
        return np.sqrt(np.mean(np.sum(d**2, axis=1)))

    plain = ov.independent_models(sim.block)
    cal = ov.independent_models(sim.block, deformation="classical", deformation_group="block")
    assert cal.converged
    assert cal.sigma0 < 0.8 * plain.sigma0
    assert rms(cal) < 0.9 * rms(plain)
    an = cal.deformation.analysis
    term = {"twist": "twist", "bend": "bend_across"}[error]
    assert an.significant[an.names.index(f"{term}@block")]


def test_unknown_sets_terms_and_groups_are_named(small):
    with pytest.raises(ov.InputError) as e:
        ov.independent_models(small.block, deformation="ebner12")
    for name in list(MODEL_SETS) + ["twist"]:
        assert name in str(e.value)
    with pytest.raises(ov.InputError, match="unknown model deformation term.*'torsion'"):
        model_ap_set(["twist", "torsion"])
    with pytest.raises(ov.InputError, match="distinct"):
        model_ap_set(["twist", "twist"])
    with pytest.raises(ov.InputError, match="deformation_group"):
        ov.independent_models(small.block, deformation="height", deformation_group="image")
    with pytest.raises(ov.InputError, match="rigorous"):
        ov.independent_models(small.block, deformation="height", method="pat-m")


def test_non_determinable_sets_name_the_correlated_pairs():
    # flat ground and standard points only: a height scale is no parameter at all, and
    # free per-model parameters are tied to the similarity of the neighbours
    sim = ov.simulate_block(
        2, 6, rng=np.random.default_rng(3), control="chains", extra=None, relief=0.0
    )
    with pytest.raises(
        ov.NotDeterminableError, match="held only by the pseudo-observation: height_scale@block"
    ):
        ov.independent_models(
            sim.block, deformation="all", deformation_group="block", deformation_sigma=None
        )
    with pytest.raises(ov.NotDeterminableError) as e:
        ov.independent_models(sim.block, deformation="all", deformation_sigma=None)
    msg = str(e.value)
    assert "correlated:" in msg and "~" in msg and "ρ=" in msg
    # with weak pseudo-observations the same set adjusts and the analysis names them
    res = ov.independent_models(sim.block, deformation="all", deformation_group="block")
    assert "height_scale@block" in res.deformation.analysis.undetermined
    assert res.deformation.sigma.shape == (1, len(TERMS))
    assert deformed is not None
