"""The free network's minimum datum holds the scale by a long base (``io/datum.py``).

Real SfM models often hold two photographs taken from almost one place (a re-shot
frame): they share the most points, but a datum on their base hangs the block's scale
on a few centimetres, the a-priori σ of every parameter grows with it and the stopping
rule (corrections below tol σ) ends the run far from the optimum.
"""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.block import Block
from orientviz.io.datum import minimum_datum
from orientviz.io.problem import problem_from_block

SHIFT_M = 0.05  # the twin's base to image K
K = 3


def _with_twin(block: Block, k: int, xy_twin: np.ndarray) -> Block:
    """``block`` and a twin of image ``k`` SHIFT_M beside it (same attitude) that sees
    the points image ``k`` sees, at ``xy_twin``."""
    o, im, cam = block.observations, block.images, block.cameras
    sel = o.image == k
    return Block.from_arrays(
        camera_c=cam.c, camera_x0=cam.x0, camera_y0=cam.y0, camera_format_mm=cam.format_mm,
        image_camera=np.r_[im.camera, im.camera[k]],
        X0=np.vstack([im.X0, im.X0[k] + [SHIFT_M, 0.0, 0.0]]),
        angles=np.vstack([im.angles, im.angles[k]]), xyz=block.points.xyz,
        obs_image=np.r_[o.image, np.full(int(sel.sum()), block.n_images)],
        obs_point=np.r_[o.point, o.point[sel]], obs_xy=np.vstack([o.xy, xy_twin]),
        obs_sigma=np.vstack([o.sigma, o.sigma[sel]]), image_ids=[*im.ids, "twin"],
        point_ids=list(block.points.ids), sequence=block.sequence,
    )  # fmt: skip


@pytest.fixture(scope="module")
def twin_block() -> Block:
    """A simulated 2 × 5 block (approximations off by ~5 m, ~1 gon) with a twin of image
    K taken 5 cm beside it; the twin's image points are projected from the truth with
    5 µm noise."""
    sim = ov.simulate_block(2, 5, rng=np.random.default_rng(3))
    n = int(np.sum(sim.block.observations.image == K))
    truth = _with_twin(sim.truth, K, np.zeros((n, 2)))
    xy = truth.project()[-n:] + np.random.default_rng(4).normal(0.0, 0.005, (n, 2))
    return _with_twin(sim.block, K, xy)


def _free_cost(block: Block, **options) -> tuple[float, object]:
    problem = problem_from_block(block)
    problem.options = dict(problem.options, free=True, **options)
    adj = ov.solve_problem(problem).adjustment
    assert adj.converged
    return adj.history[-1].cost, adj


def test_the_minimum_datum_holds_a_long_base(twin_block):
    ids = twin_block.images.ids
    _, note = minimum_datum(twin_block)
    held = [i for i in ids if f"image {i} " in note]
    assert len(held) == 2 and {ids[K], "twin"} != set(held)  # not the 5 cm pair
    X0 = twin_block.images.X0
    base = np.linalg.norm(X0[ids.index(held[0])] - X0[ids.index(held[1])])
    assert base > 100 * SHIFT_M


def test_the_free_network_reaches_the_optimum_of_a_long_base(twin_block):
    ids = twin_block.images.ids
    free, _ = _free_cost(twin_block)
    # the same network with a datum chosen by hand: image 0 and X0 of the strip's last
    # image (a base of ~3.7 km); vᵀPv does not depend on the datum
    hand, _ = _free_cost(twin_block, fix=[ids[0], f"{ids[4]}:X0"])
    assert free == pytest.approx(hand, rel=1e-9)  # the 5 cm datum stops 1e-3 above
