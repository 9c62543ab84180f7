"""Starts that converge: approximations in another frame than the control are aligned first."""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
from orientviz.block import CONTROL, TIE
from orientviz.bundle import bundle_adjust
from orientviz.errors import InputError
from orientviz.io.kinds._align import align_to_control
from orientviz.io.kinds.block import solve
from orientviz.io.problem import dumps_problem, loads_problem, problem_from_block
from orientviz.orientation.absolute import SimilarityTransform
from orientviz.rotation import matrix_from_opk, opk_from_matrix

T = SimilarityTransform(0.01, matrix_from_opk(0.3, -0.2, 1.1), np.array([5.0, -3.0, 2.0]))


def _moved(block):
    """The block's approximations carried into an arbitrary frame (a COLMAP-like model)."""
    c = block.copy()
    c.images.X0 = T.apply(block.images.X0)
    c.images.angles = np.column_stack(
        opk_from_matrix(T.R[None] @ block.rotations(), block.sequence)
    )
    tie = c.points.role == TIE
    c.points.xyz[tie] = T.apply(block.points.xyz[tie])
    return c


def _solve(block):
    return solve(loads_problem(dumps_problem(problem_from_block(block)), "b.json"), "bundle")


@pytest.fixture(scope="module")
def block():
    return ov.simulate_block(2, 6, rng=3, control="perimeter").block


def test_a_block_in_another_frame_converges_to_the_same_optimum(block):
    moved = _moved(block)
    assert not bundle_adjust(moved, control="fixed").converged  # the bundle alone diverges
    ref, sol = _solve(block), _solve(moved)
    assert sol.adjustment.converged
    assert sol.adjustment.sigma0 == pytest.approx(ref.adjustment.sigma0, rel=1e-9)
    assert np.allclose(sol.X0, ref.X0, atol=1e-6)
    assert "aligned to the control first" in sol.notes[0]
    scale = float(sol.notes[0].split("scale ")[1].split(",")[0])
    assert scale == pytest.approx(1 / T.scale, rel=0.02)  # the start values are a few m off


def test_approximations_in_the_control_frame_are_left_alone(block):
    out, al = align_to_control(block)
    assert out is block and not al.applied


def test_too_few_control_points_say_so_and_name_the_datum_choices(block):
    moved = _moved(block)
    ctrl = np.flatnonzero(moved.points.role == CONTROL)
    moved.points.role[ctrl[2:]] = TIE
    moved.points.xyz_known[ctrl[2:]] = np.nan
    moved.points.sigma[ctrl[2:]] = np.nan
    with pytest.raises(InputError) as info:
        align_to_control(moved)
    msg = str(info.value)
    assert "another frame" in msg and "3 non-collinear" in msg and "free network" in msg


def test_a_model_that_does_not_fit_is_reported_as_such(block):
    """Image errors ten times their stated σ (e.g. a wrong pixel size): σ0 ≫ 1, most flagged."""
    bad = block.copy()
    rng = np.random.default_rng(5)
    bad.observations.xy = bad.observations.xy + rng.normal(0, 0.05, bad.observations.xy.shape)
    sol = _solve(bad)
    assert sol.adjustment.sigma0 > 3
    assert sol.notes[0].startswith("warning: the model does not fit the data")
    assert "DOES NOT FIT" in sol.as_text()
    good = _solve(block)
    assert not any("does not fit" in n for n in good.notes)
