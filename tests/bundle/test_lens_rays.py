"""The camera model on a block's rays with only its active terms (bundle.model._lens_rays).

:func:`lens_rays` skips idle parameters and forms only the estimated derivatives; every
result must be the full model's (:func:`evaluate_lens`, itself checked against central
differences in test_lens_model.py) on the same rays.
"""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.bundle.model import evaluate_lens
from orientviz.bundle.model._lens_rays import lens_rays

THETA = {
    "backward": [7.31, 0.03, -0.02, 2e-4, 1e-4, 4e-3, -4e-5, -2e-6, -6e-5, -4e-5],
    "forward": [7.31, 0.03, -0.02, 2e-4, 1e-4, -0.1, 0.05, 0.02, 1e-3, -5e-4],
}


def _cases(kind: str, count: int, seed: int):
    """Random cameras: 1–3 groups, some parameters zero, a random estimated subset."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        G, n = int(rng.integers(1, 4)), 40
        th = np.tile(THETA[kind], (G, 1)) * rng.uniform(0.5, 1.5, (G, 10))
        zero = rng.random(10) < 0.5
        zero[0] = False  # c > 0
        th[:, zero] = 0.0
        if rng.random() < 0.3:
            th[:] = th[0]  # all groups alike: the parameters act as scalars
        est = np.sort(rng.choice(10, int(rng.integers(1, 11)), replace=False))
        grp = rng.integers(0, G, n)
        nrm = rng.uniform(-0.4, 0.4, (n, 2))
        m = rng.uniform(-3.0, 3.0, (n, 2))
        yield th, grp, nrm, m, est, rng.uniform(0.5, 2.0, (G, est.size))


@pytest.mark.parametrize("kind", ["backward", "forward"])
def test_the_active_terms_give_the_full_models_values(kind):
    idle_seen = 0
    for th, grp, nrm, m, est, scale in _cases(kind, 150, seed=11):
        f0, M0, D0 = evaluate_lens(kind, th[grp], nrm, m)
        D0 = D0[:, :, est] * scale[grp][:, None, :]
        f, M, D = lens_rays(kind, th, grp, nrm, m, est, scale)
        assert D.shape == D0.shape
        for new, full in ((f, f0), (M, M0), (D, D0)):
            assert np.max(np.abs(new - full)) <= 1e-15 * np.max(np.abs(full))
        if kind == "backward":  # the same operations in the same order: the same numbers
            assert np.array_equal(f, f0) and np.array_equal(M, M0) and np.array_equal(D, D0)
        assert np.array_equal(lens_rays(kind, th, grp, nrm, m, est, scale, False)[0], f)
        idle_seen += int(np.any(np.all(th == 0.0, axis=0)))
    assert idle_seen > 50  # the cases had idle parameters to skip


def test_an_estimated_parameter_at_zero_keeps_its_derivative():
    # a BAL camera at its start: f, k1, k2 estimated, k1 = k2 = 0 and everything else idle
    c = 7.31
    th = np.zeros((1, 10))
    th[0, 0] = c
    rng = np.random.default_rng(2)
    nrm = rng.uniform(-0.4, 0.4, (9, 2))
    est = np.array([0, 5, 6])
    f, M, D = lens_rays("forward", th, np.zeros(9, np.int64), nrm, np.zeros((9, 2)), est,
                        np.ones((1, 3)))  # fmt: skip
    r2 = np.sum(nrm**2, axis=1)[:, None]
    assert np.allclose(f, c * nrm, rtol=1e-15, atol=0.0)  # the pinhole
    assert np.allclose(M, c * np.eye(2), rtol=1e-15, atol=0.0)
    assert np.allclose(D[:, :, 0], nrm, rtol=1e-15, atol=0.0)  # ∂f/∂c
    assert np.allclose(D[:, :, 1], c * nrm * r2, rtol=1e-15, atol=0.0)  # ∂f/∂k1
    assert np.allclose(D[:, :, 2], c * nrm * r2**2, rtol=1e-14, atol=0.0)  # ∂f/∂k2
