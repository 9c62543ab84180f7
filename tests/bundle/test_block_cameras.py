"""``bundle_adjust(block)`` estimates what the block's cameras state, as ``orientviz solve`` does.

A block read from a file or imported (COLMAP, BAL, DBAT) carries per camera a lens model
or an additional-parameter set (``block.cameras.model``). The library and the command line
must solve the same model for the same block; keywords given by the caller win.
"""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
import orientviz.bundle.loop._adjust as adjust_module
from orientviz.bundle import LensModel, block_camera_options
from orientviz.bundle._block_cameras import held_plain_camera
from orientviz.bundle.model import BoundLens
from orientviz.errors import InputError
from orientviz.io.colmap_lens import forward_camera
from orientviz.io.problem import problem_from_block

#: What ``read_colmap`` states for a SIMPLE_PINHOLE camera (COLMAP refines f).
FREE_C = {"model": "forward", "free": ["c"], "sigma": {}, "values": {}, "r0": None}
#: What ``read_colmap(..., lens="fixed")`` states for a PINHOLE camera with fx = fy: a
#: forward lens model, nothing free, as = 0 (the values of c, x0, y0 are the block's).
HELD = forward_camera("PINHOLE", {"fx": 1280.0, "fy": 1280.0, "cx": 512.0, "cy": 384.0},
                      0.01, "fixed")[3]  # fmt: skip
EBNER = {"additional": "ebner12", "additional_sigma": None, "free": None, "sigma": {}}


def _block(spec: dict | None, c_error: float = 0.0):
    """A small simulated aerial block (10 images, 4 control points) whose camera states
    ``spec``; ``c_error`` (mm) is added to the camera's principal distance."""
    b = ov.simulate_block(2, 5, rng=np.random.default_rng(7)).block
    b.cameras.c = b.cameras.c + c_error
    b.cameras.model = [] if spec is None else [dict(spec)]
    return b


@pytest.fixture(scope="module")
def plain():
    return ov.bundle_adjust(_block(None, 0.02))


def test_the_library_estimates_the_block_camera_model_as_solve_does(plain):
    block = _block(FREE_C, 0.02)
    lib = ov.bundle_adjust(block)
    sol = ov.solve_problem(problem_from_block(block))  # what `orientviz solve` runs
    assert lib.camera is not None and lib.camera.estimated[0]  # c is estimated
    assert lib.redundancy == plain.redundancy - 1 == sol.counts()["redundancy"]
    assert lib.sigma0 == pytest.approx(sol.adjustment.sigma0, rel=1e-12)
    np.testing.assert_allclose(lib.exterior, sol.adjustment.exterior, rtol=0, atol=1e-9)
    # c is an unknown: it moves from its start (152.02 mm) within 3σ of the simulation's
    # 152 mm, and vᵀPv falls below the run that holds it
    c, s = lib.camera.get("c")
    assert c != 152.02 and abs(c - 152.0) < 3 * s
    assert lib.redundancy * lib.sigma0**2 < plain.redundancy * plain.sigma0**2


def test_given_keywords_win_over_the_block(plain):
    block = _block(FREE_C, 0.02)
    none = ov.bundle_adjust(block, additional=False)
    assert none.camera is None and none.redundancy == plain.redundancy
    np.testing.assert_array_equal(none.x, plain.x)  # the same run as a block without model
    two = ov.bundle_adjust(block, additional=LensModel("forward", free=("c", "k1")))
    assert two.redundancy == plain.redundancy - 2
    assert [n for n, e in zip(two.camera.names, two.camera.estimated) if e] == ["c", "k1"]


def test_an_additional_set_of_the_block_is_one_group_per_camera(plain):
    block = _block(EBNER)
    opts = block_camera_options(block)
    assert opts["ap_group"].tolist() == block.images.camera.tolist()
    own = ov.bundle_adjust(block)
    given = ov.bundle_adjust(block, **opts)
    np.testing.assert_array_equal(own.x, given.x)
    assert own.redundancy == plain.redundancy - 12
    # ap_sigma given by the caller replaces the block's (every parameter held at 0 here)
    held = ov.bundle_adjust(block, ap_sigma=np.full(12, 1e-6))
    assert np.abs(held.additional).max() < 1e-3


def test_cameras_that_state_different_models_are_refused():
    block = _block(FREE_C)
    block.cameras.ids = ["a", "b"]
    block.cameras.c = np.repeat(block.cameras.c, 2)
    block.cameras.x0, block.cameras.y0 = np.zeros(2), np.zeros(2)
    block.cameras.format_mm = np.repeat(block.cameras.format_mm, 2, axis=0)
    block.cameras.model = [dict(FREE_C), dict(EBNER)]
    block.images.camera[5:] = 1
    with pytest.raises(InputError, match="camera 'b': every camera of a block must state"):
        ov.bundle_adjust(block)


def _count_lens_projections(monkeypatch) -> list:
    """Record every projection through a lens model (the lens path's only way to
    predict a ray)."""
    calls: list = []
    real = BoundLens.evaluate

    def spy(self, *args, **kwargs):
        calls.append(self.model.kind)
        return real(self, *args, **kwargs)

    monkeypatch.setattr(BoundLens, "evaluate", spy)
    return calls


def test_a_held_lens_without_distortion_is_solved_as_the_plain_model(plain, monkeypatch):
    assert HELD["free"] == [] and set(HELD["values"].values()) == {0.0}
    block = _block(HELD, 0.02)
    calls = _count_lens_projections(monkeypatch)
    res = ov.bundle_adjust(block)
    assert calls == []  # no ray went through the lens model
    np.testing.assert_array_equal(res.x, plain.x)  # the plain run, bit for bit
    assert (res.iterations, res.sigma0, res.redundancy) == (
        plain.iterations, plain.sigma0, plain.redundancy)  # fmt: skip
    # `orientviz solve` takes the same path
    sol = ov.solve_problem(problem_from_block(block)).adjustment
    assert calls == []
    np.testing.assert_array_equal(sol.x, plain.x)
    # the camera is still reported, as the lens model's own run reports it
    monkeypatch.setattr(adjust_module, "held_plain_camera", lambda *args: None)
    lens = ov.bundle_adjust(block)
    assert calls and set(calls) == {"forward"}  # this run did take the lens path
    for field in ("value", "sigma", "estimated", "r0"):
        np.testing.assert_array_equal(getattr(res.camera, field), getattr(lens.camera, field))
    np.testing.assert_array_equal(sol.camera.value, lens.camera.value)
    assert not res.camera.estimated.any() and res.camera.value[0, 0] == block.cameras.c[0]
    # ... and the two are one model: the same optimum to rounding (8e-11 m on coordinates
    # of 4.7 km, 1e-14 relative, when measured)
    assert lens.iterations == res.iterations
    assert lens.sigma0 == pytest.approx(res.sigma0, rel=1e-12)
    np.testing.assert_allclose(lens.exterior[:, :3], res.exterior[:, :3], rtol=0, atol=1e-9)
    np.testing.assert_allclose(lens.exterior[:, 3:], res.exterior[:, 3:], rtol=0, atol=1e-13)
    np.testing.assert_allclose(lens.points, res.points, rtol=0, atol=1e-9)


@pytest.mark.parametrize(
    "model",
    [
        LensModel("forward", free=(), values={"k1": 1e-3}),  # distortion held, not zero
        LensModel("forward", free=(), values={"as": 1e-4}),  # an affinity
        LensModel("backward", free=(), values={"sk": 1e-4}),
        LensModel("forward", free=("k1",)),  # something estimated
        LensModel("forward", free=(), prior={"c": 0.01}),  # a weighted c
        LensModel("forward", free=(), values={"c": 152.0}),  # another c than the camera's
    ],
)
def test_a_lens_model_that_is_not_the_plain_one_keeps_the_lens_path(model):
    block = _block(None, 0.02)
    used = np.ones(block.observations.image.size, bool)
    assert held_plain_camera(block, model, None, used) is None
    zero = LensModel(model.kind, free=())
    assert held_plain_camera(block, zero, None, used) is not None  # the same kind, held at 0
