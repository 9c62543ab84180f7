"""The camera model inside the bundle's projection (orientviz.bundle.LensModel)."""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.bundle import LensModel, bundle_adjust
from orientviz.bundle.model import BACKWARD_NAMES, FORWARD_NAMES, evaluate_lens
from orientviz.errors import InputError
from orientviz.lens import BackwardLens, backward_ideal
from orientviz.simulate import simulate_calibration

BACK = {"c": 7.31, "x0": 0.03, "y0": -0.02, "as": 2e-4, "sk": 1e-4, "K1": 4e-3, "K2": -4e-5,
        "K3": -2e-6, "P1": -6e-5, "P2": -4e-5}  # fmt: skip
FWD = {"c": 7.31, "x0": 0.03, "y0": -0.02, "as": 2e-4, "sk": 1e-4, "k1": -0.1, "k2": 0.05,
       "k3": 0.02, "p1": 1e-3, "p2": -5e-4}  # fmt: skip


def _theta(kind):
    cam, names = (BACK, BACKWARD_NAMES) if kind == "backward" else (FWD, FORWARD_NAMES)
    return np.array([cam[k] for k in names])


def _central(kind, th, nrm, m, which, j, h):
    """Central difference of f by column j of θ (which = 0) or of n (which = 1)."""
    args = [th, nrm]
    plus, minus = args[which].copy(), args[which].copy()
    plus[:, j] += h
    minus[:, j] -= h
    f = [evaluate_lens(kind, *((a if w == which else b) for w, b in enumerate(args)), m, False)[0]
         for a in (plus, minus)]  # fmt: skip
    return (f[0] - f[1]) / (2 * h)


@pytest.mark.parametrize("kind", ["backward", "forward"])
def test_derivatives_equal_central_differences(kind):
    rng = np.random.default_rng(3)
    n = 7
    th = np.tile(_theta(kind), (n, 1))
    nrm = rng.uniform(-0.4, 0.4, (n, 2))
    m = rng.uniform(-3.0, 3.0, (n, 2))
    f, M, D = evaluate_lens(kind, th, nrm, m)
    for j in range(10):
        num = _central(kind, th, nrm, m, 0, j, 1e-5 * max(abs(th[0, j]), 1e-2))
        assert np.allclose(D[:, :, j], num, rtol=1e-6, atol=1e-9), (kind, j)
    for j in range(2):
        num = _central(kind, th, nrm, m, 1, j, 1e-7)
        assert np.allclose(M[:, :, j], num, rtol=1e-6, atol=1e-8), (kind, j)


def test_backward_model_is_the_lens_modules_ideal_point():
    rng = np.random.default_rng(4)
    m = rng.uniform(-3.0, 3.0, (9, 2))
    nrm = rng.uniform(-0.4, 0.4, (9, 2))
    th = _theta("backward")
    f = evaluate_lens("backward", np.tile(th, (9, 1)), nrm, m, False)[0]
    lens = BackwardLens(th[0], th[1], th[2], tuple(th[5:8]), tuple(th[8:10]), th[3], th[4])
    # f = m + c·n − x̄(m): the residual f − m is the pinhole minus the corrected point
    assert np.allclose(f - m, th[0] * nrm - backward_ideal(m, lens), atol=1e-14)


@pytest.mark.parametrize("kind", ["backward", "forward"])
def test_recovers_the_true_camera_from_noise_free_images(kind):
    cam = dict(BACK if kind == "backward" else FWD, sk=0.0)
    sim = simulate_calibration(np.random.default_rng(1), kind=kind, camera=cam, sigma_mm=1e-9)
    res = bundle_adjust(sim.block, additional=LensModel(kind), tol=1e-9, max_iter=50)
    assert res.converged
    for name, true in cam.items():
        value, sigma = res.camera.get(name)
        assert abs(value - true) <= 5 * sigma, name  # within its σ (noise 1e-9 mm; sk fixed)
        assert sigma < 1e-4 * max(abs(true), 1e-2), name  # and σ is small: a sharp test
    assert np.max(np.abs(res.exterior - sim.exterior)) < 1e-7
    # the nominal start (c = 7.3, no distortion) is far from the truth: the model moved
    assert abs(res.camera.get("c")[0] - sim.block.cameras.c[0]) > 5e-3


def test_without_distortion_the_model_is_the_plain_projection():
    sim = simulate_calibration(np.random.default_rng(2), sigma_mm=3e-4)
    plain = bundle_adjust(sim.block)
    fixed = bundle_adjust(sim.block, additional=LensModel("forward", free=()))
    assert fixed.camera is not None and not fixed.camera.estimated.any()
    assert abs(plain.sigma0 - fixed.sigma0) < 1e-9 * plain.sigma0
    assert np.allclose(plain.exterior, fixed.exterior, atol=1e-9)


def test_prior_sigma_is_a_pseudo_observation_and_fixed_values_stay():
    sim = simulate_calibration(np.random.default_rng(5), camera={"K1": 4e-3, "c": 7.31})
    free = bundle_adjust(sim.block, additional=LensModel("backward", free=("c", "K1")))
    held = bundle_adjust(
        sim.block,
        additional=LensModel("backward", free=("K1",), prior={"c": 1e-5}, values={"K2": 1e-5}),
    )
    assert held.redundancy == free.redundancy + 1  # the prior on c is one more observation
    assert abs(held.camera.get("c")[0] - 7.3) < 5e-5  # held near its given value
    assert abs(free.camera.get("c")[0] - 7.31) < 5e-4  # free: found
    assert held.camera.get("K2") == (1e-5, 0.0)  # fixed at the given value


@pytest.mark.parametrize(
    "kwargs, words",
    [
        ({"kind": "fisheye"}, "kind expected one of backward, forward"),
        ({"free": ("K4",)}, "free: unknown parameter 'K4'"),
        ({"kind": "forward", "free": ("K1",)}, "unknown parameter 'K1'"),
        ({"prior": {"c": -1.0}}, "prior σ of c"),
        ({"r0": 0.0}, "r0 expected a positive radius"),
    ],
)
def test_bad_models_get_one_clear_line(kwargs, words):
    with pytest.raises(InputError, match=words.replace("(", r"\(")) as e:
        LensModel(**kwargs)
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("kind", ["backward", "forward"])
def test_check_points_are_intersected_through_the_estimated_camera(kind):
    cam = dict(BACK if kind == "backward" else FWD, sk=0.0)
    sim = simulate_calibration(np.random.default_rng(6), kind=kind, camera=cam, sigma_mm=1e-4)
    pts = sim.block.points
    chk = np.flatnonzero(pts.role == 0)[::9]  # every ninth target: a check point
    pts.role[chk] = 2
    pts.xyz_known[chk] = sim.points[chk]
    res = bundle_adjust(sim.block, additional=LensModel(kind), tol=1e-9, max_iter=50)
    err = np.abs(res.check_points.difference)
    assert chk.size >= 8 and np.max(err) < 1e-4  # m, on a 1 m field (image σ 0.1 µm)
    # the same rays intersected as if the camera had no lens miss by far more
    plain = bundle_adjust(sim.block, additional=LensModel(kind, free=()), max_iter=50)
    assert np.max(np.abs(plain.check_points.difference)) > 100 * np.max(err)


def test_a_forward_camera_in_opencvs_terms_projects_as_opencv_does():
    from orientviz.bundle.model._lens import LensEstimates, opencv_camera
    from orientviz.lens import forward_pixels

    th = _theta("forward").copy()
    th[4] = 0.0  # forward_pixels (OpenCV's formula, orientviz.lens) has no skew
    est = LensEstimates("forward", FORWARD_NAMES, ("",) * 10, th[None], np.zeros((1, 10)),
                        np.ones(10, bool), np.full((1, 10, 10), np.nan), np.ones(1))  # fmt: skip
    p = 0.0032
    cv = opencv_camera(est, p)
    rng = np.random.default_rng(8)
    nrm = rng.uniform(-0.4, 0.4, (9, 2))  # orientviz's normalised points (y up)
    f = evaluate_lens("forward", np.tile(th, (9, 1)), nrm, np.zeros((9, 2)), False)[0]
    uv = forward_pixels(nrm * [1, -1], [cv[k] for k in ("fx", "fy", "cx", "cy", "k1", "k2",
                                                         "k3", "p1", "p2")])  # fmt: skip
    assert np.allclose(uv, f * [1 / p, -1 / p], atol=1e-9)  # pixels: x/p, −y/p
    with pytest.raises(InputError, match="forward model is needed"):
        opencv_camera(LensEstimates("backward", BACKWARD_NAMES, *[getattr(est, a) for a in (
            "units", "value", "sigma", "estimated", "correlation", "r0")]), p)  # fmt: skip
