"""Per-image cameras inside the images' blocks of the reduced system.

A camera model with a camera of its own per image (BAL, COLMAP models with a camera per
image) puts each camera's parameters into its image's block of the reduced system
(``bundle.problem._camera_blocks``) instead of a border. Checked against the textbook
reference's optimum, step by step against the border path on the same problem, and its
border form (E, F, H: what the precision reads) against the border's own formation.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_reference import assert_same_optimum, one_blas_thread  # noqa: F401

import orientviz as ov
import orientviz.bundle.problem._problem as problem_module
from orientviz.bundle import BundleOptions, LensModel
from orientviz.bundle.reduced import ReducedOptions
from orientviz.bundle.reference import reference_bundle
from orientviz.errors import NotDeterminableError
from orientviz.simulate import simulate_calibration

#: S formed by pairs of rays and factored densely (the path's conditions; the small test
#: block would otherwise be formed densely)
OPTIONS = BundleOptions(solver="dense", reduced=ReducedOptions(pair_ns=1e-3))


def _lens() -> LensModel:
    return LensModel("forward", free=("c", "k1", "k2"))


@pytest.fixture(scope="module")
def per_image():
    """12 images of a calibration field, each its own camera (c, k1, k2 free)."""
    block = simulate_calibration(np.random.default_rng(1), kind="forward", sigma_mm=3e-4).block
    group = np.arange(block.n_images)
    ref = reference_bundle(block, additional=_lens(), ap_group=group, tol=1e-8, max_iter=50)
    return block, group, ref


def _solve(block, group, **kw):
    return ov.bundle_adjust(block, additional=_lens(), ap_group=group, tol=1e-8, max_iter=50,
                            options=OPTIONS, **kw)  # fmt: skip


def test_the_camera_blocks_reach_the_reference_optimum(per_image):
    block, group, ref = per_image
    res = _solve(block, group)
    assert set(res.reduced_info["ap_border"]) - {"held"} == {"camera blocks"}
    assert_same_optimum(res, ref, block)


def test_the_camera_blocks_take_the_border_paths_steps(per_image, monkeypatch):
    block, group, _ = per_image
    blocks = _solve(block, group)
    monkeypatch.setattr(problem_module, "camera_blocks_apply", lambda prob: False)
    border = _solve(block, group)
    assert "camera blocks" not in border.reduced_info["ap_border"]
    # the same damped steps: every iterate's cost to rounding, the same precision
    assert len(blocks.history) == len(border.history)
    for a, b in zip(blocks.history, border.history):
        assert abs(a.cost - b.cost) <= 1e-11 * b.cost
    sa, sb = blocks.std(), border.std()
    held = sb == 0
    assert np.array_equal(sa == 0, held)
    assert np.max(np.abs(sa[~held] - sb[~held]) / sb[~held]) < 1e-8


@pytest.mark.parametrize("lam", [0.0, 1e-3])
def test_the_border_form_of_the_camera_blocks_is_the_borders(per_image, monkeypatch, lam):
    # one linearisation, formed both ways: E, F (undamped and damped), the right-hand
    # side and H, the point couplings the precision and the back-substitution read
    block, group, _ = per_image
    captured = []
    real = problem_module.BundleProblem.normal
    monkeypatch.setattr(
        problem_module.BundleProblem,
        "normal",
        lambda self, *a, **k: captured.append((self, a)) or real(self, *a, **k),
    )
    _solve(block, group, precision=False)
    prob, (st, rw, Je, Jp, *_) = captured[1]
    ne = prob.normal(st, rw, Je, Jp, lam)
    assert ne.ext is not None
    prob.camera_blocks = False
    ref = prob.normal(st, rw, Je, Jp, lam)
    assert ref.ext is None
    for x, y in (
        (ne.ap.E, ref.ap.E),
        (ne.ap.F0, ref.ap.F0),
        (ne.ap.F, ref.ap.F),
        (ne.ap.ba, ref.ap.ba),
        (ne.ap.H, ref.ap.H),
        (ne.blocks, ref.blocks),
        (ne.rhs, ref.rhs),
        (ne.diagF, ref.diagF),
    ):
        assert np.max(np.abs(x - y)) <= 1e-11 * np.max(np.abs(y))
    assert np.array_equal(ne.diagU, ref.diagU) and np.array_equal(ne.diagV, ref.diagV)


def test_cameras_that_are_not_determinable_are_named_as_by_the_border(per_image, monkeypatch):
    # every parameter of a camera free per image (x0, y0 with the exterior, …): singular
    block, group, _ = per_image
    free = ("c", "x0", "y0", "as", "sk", "k1", "k2", "k3", "p1", "p2")
    errors = []
    for camera_blocks in (True, False):
        if not camera_blocks:
            monkeypatch.setattr(problem_module, "camera_blocks_apply", lambda prob: False)
        with pytest.raises(NotDeterminableError) as err:
            ov.bundle_adjust(block, additional=LensModel("forward", free=free), ap_group=group,
                             max_iter=3, options=OPTIONS)  # fmt: skip
        errors.append((str(err.value), err.value.parameters))
    assert errors[0] == errors[1]
    assert "c@g11" in errors[0][1]
