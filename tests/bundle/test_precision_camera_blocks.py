"""The precision of a bundle whose cameras are per image, from its camera blocks.

With a camera of its own per image the bundle's reduced system is formed in blocks of
d = 6 + k unknowns per image (``bundle.problem._camera_blocks``) and the precision is
computed from those blocks (``bundle.precision._camera``). Checked against the textbook
inverse (S⁻¹ over the exterior and camera unknowns, N22⁻¹ + Tᵀ Q11 T for the points) at
the optimum, with the tolerance the border path meets on the same block, and against the
redundancy's own sum (Σ r = n − u).
"""

from __future__ import annotations

import numpy as np
import pytest
from test_reference import one_blas_thread, textbook_cofactors  # noqa: F401

import orientviz as ov
import orientviz.bundle.precision._precision as precision_module
import orientviz.bundle.problem._problem as problem_module
from orientviz.bundle import BundleOptions, LensModel
from orientviz.bundle.reduced import ReducedOptions
from orientviz.bundle.reference import reference_bundle, reference_data
from orientviz.simulate import simulate_calibration

#: S formed by pairs of rays and factored densely: the camera blocks' conditions
OPTIONS = BundleOptions(solver="dense", reduced=ReducedOptions(pair_ns=1e-3))
#: The runs stop where the corrections are below 1e-10 of their σ, the reference at 1e-9:
#: on this well-conditioned field the cofactors of both paths then agree with the
#: textbook's to 3e-13–5e-13 (measured); the bound leaves room for other BLAS builds.
RTOL = 1e-10


def _lens() -> LensModel:
    return LensModel("forward", free=("c", "k1", "k2"))


@pytest.fixture(scope="module")
def field():
    """12 images of a calibration field, each its own camera (c, k1, k2 free; camera g of
    image i not g = i, as the parameters' order must be kept), and the textbook cofactors
    at the reference optimum."""
    block = simulate_calibration(np.random.default_rng(1), kind="forward", sigma_mm=3e-4).block
    group = np.roll(np.arange(block.n_images), 5)
    ref = reference_bundle(block, additional=_lens(), ap_group=group, tol=1e-9, max_iter=60)
    data = reference_data(block, "fixed", _lens(), group, None)
    Q11, Q22 = textbook_cofactors(data, ref, block.sequence)
    return block, group, ref, data, Q11, Q22


def _solve(block, group):
    return ov.bundle_adjust(block, additional=_lens(), ap_group=group, tol=1e-10, max_iter=80,
                            options=OPTIONS)  # fmt: skip


def _assert_textbook(res, field):
    block, _, ref, data, Q11, Q22 = field
    s0 = np.sqrt(ref.cost[-1] / res.redundancy)
    std = res.std()
    m = block.n_images
    q11 = np.diag(Q11)
    np.testing.assert_allclose(std[res.groups["exterior"]], s0 * np.sqrt(q11[: 6 * m]), rtol=RTOL)
    np.testing.assert_allclose(std[res.groups["additional"]], s0 * np.sqrt(q11[6 * m :]), rtol=RTOL)
    got = std[res.groups["points"]].reshape(-1, 3)[data.unknown]
    np.testing.assert_allclose(got, s0 * np.sqrt(np.einsum("pii->pi", Q22)), rtol=RTOL)
    # the full 6 × 6 blocks of the images, not only their diagonals
    Qe = res.cofactor_groups["exterior"]
    for i in (0, m // 2, m - 1):
        np.testing.assert_allclose(
            Qe[i], Q11[6 * i : 6 * i + 6, 6 * i : 6 * i + 6], rtol=RTOL, atol=RTOL * Qe[i].max()
        )
    # the redundancy numbers add up to the redundancy (Σ r = n − u)
    assert abs(res.redundancy_check - res.redundancy) < 1e-10 * res.redundancy


def test_the_camera_blocks_precision_is_the_textbook_inverse(field, monkeypatch):
    block, group = field[:2]
    used = []
    real = precision_module.camera_precision
    monkeypatch.setattr(precision_module, "camera_precision", lambda *a: used.append(1) or real(*a))
    res = _solve(block, group)
    assert set(res.reduced_info["ap_border"]) - {"held"} == {"camera blocks"}
    assert used == [1]  # computed from the camera blocks
    _assert_textbook(res, field)


def test_the_border_path_meets_the_same_tolerance(field, monkeypatch):
    block, group = field[:2]
    monkeypatch.setattr(problem_module, "camera_blocks_apply", lambda prob: False)
    res = _solve(block, group)
    assert "camera blocks" not in res.reduced_info["ap_border"]
    _assert_textbook(res, field)
