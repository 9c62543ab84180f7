"""orientviz.plausibility finds each implausible geometry, and nothing on a sound block."""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.errors import AdjustmentError, InputError
from orientviz.plausibility import check_block, raise_for


@pytest.fixture(scope="module")
def sim():
    from orientviz.simulate import simulate_block

    return simulate_block(2, 6, rng=3, control="perimeter", n_check=2)


def _checks(block, **kw):
    return {f.check: f for f in check_block(block, **kw)}


def test_a_sound_block_has_no_findings(sim):
    assert check_block(sim.block) == []
    assert check_block(sim.truth) == []


def test_image_coordinate_far_outside_is_an_input_error_at_its_place(sim):
    b = sim.block.copy()
    b.observations.xy[17, 0] = -1e308
    f = _checks(b, place=lambda k: f"observations[{k}]")["image-outside"]
    assert (f.level, f.exit_code, f.place) == ("error", 2, "observations[17]")
    assert repr(b.images.ids[b.observations.image[17]]) in f.message
    with pytest.raises(InputError, match="observation 17: x = -1e"):
        raise_for(check_block(b), "f.json")


def test_points_above_the_cameras_are_behind_them(sim):
    b = sim.truth.copy()
    b.points.xyz[:, 2] += 5000.0
    b.points.xyz_known[:, 2] += 5000.0
    f = _checks(b)["behind"]
    assert f.level == "error" and f.count == b.n_observations
    with pytest.raises(AdjustmentError, match="behind"):
        raise_for([f], "f.json")


def test_a_few_points_behind_are_a_warning(sim):
    b = sim.truth.copy()
    tie = int(np.flatnonzero(b.points.role == 0)[0])
    b.points.xyz[tie, 2] = 1e4  # one tie point far above the cameras
    f = _checks(b)["behind"]
    assert f.level == "warning"
    assert f.count == int(np.sum(b.observations.point == tie))


def test_an_image_with_two_points_has_fewer_observations_than_unknowns(sim):
    b = sim.block.copy()
    i = b.observations.image
    keep = (i != 0) | (np.cumsum(i == 0) <= 2)
    b = b.subset_observations(keep) if hasattr(b, "subset_observations") else _subset(b, keep)
    f = _checks(b)["few-observations"]
    assert repr(b.images.ids[0]) in f.message and f.exit_code == 3
    assert "few-observations" not in _checks(b, exterior_unknown=False)


def _subset(block, keep):
    out = block.copy()
    o = out.observations
    o.image, o.point, o.xy, o.sigma = o.image[keep], o.point[keep], o.xy[keep], o.sigma[keep]
    return out


def test_rays_from_nearly_the_same_place_meet_at_a_small_angle(sim):
    b = _subset(sim.truth, np.isin(sim.truth.observations.image, [0, 1]))
    assert "weak-intersection" not in _checks(b)
    from orientviz.camera import project

    b.images.X0[1] = b.images.X0[0] + [5.0, 0.0, 0.0]  # a 5 m base at 1.5 km
    b.images.angles[1] = b.images.angles[0]
    R = b.rotations()[1]
    o = b.observations
    sel = o.image == 1
    o.xy[sel] = project(b.points.xyz[o.point[sel]], b.images.X0[1], R, b.cameras.c[0], 0.0, 0.0)
    f = _checks(b)["weak-intersection"]
    assert f.level == "warning" and f.count > 0


def test_a_point_far_away_is_a_warning_and_an_absurd_one_an_error(sim):
    b = sim.block.copy()
    b.points.xyz[3] += 1e6
    assert _checks(b)["far-away"].level == "warning"
    b.points.xyz[3] = 1e14
    assert _checks(b)["far-away"].level == "error"


def test_warnings_are_logged_and_errors_raised_in_order(sim, caplog):
    b = sim.block.copy()
    b.points.xyz[3] += 1e6
    with caplog.at_level("WARNING", logger="orientviz"):
        warnings = raise_for(check_block(b), "f.json")
    assert "far-away" in [w.check for w in warnings]
    assert any(
        "far outside" in r.getMessage() and "f.json" in r.getMessage() for r in caplog.records
    )


def test_far_points_are_named_farthest_first_with_the_largest_distance(sim):
    """The message names the farthest point first and its distance ("up to"), not the
    distance of whichever far point comes first in the file."""
    b = sim.block.copy()
    near, farther = np.flatnonzero(~np.isfinite(b.points.xyz_known).any(axis=1))[:2]
    b.points.xyz[near] += 1e6
    b.points.xyz[farther] += 1e8
    f = _checks(b)["far-away"]
    xyz = np.where(np.isfinite(b.points.xyz_known), b.points.xyz_known, b.points.xyz)
    centre = np.median(np.concatenate([xyz, b.images.X0]), axis=0)
    largest = float(np.max(np.abs(xyz[farther] - centre)))
    ids = b.points.ids
    assert f.message.startswith(f"point {ids[farther]!r}, point {ids[near]!r} lie up to")
    assert f"up to {largest:.3g} " in f.message


def test_one_far_point_lies_and_the_solve_says_the_check_saw_the_file(sim):
    """One far point: "lies" (singular). In a solution's notes the input checks say that
    they looked at the file's values, not at the solution listed beside them."""
    from orientviz.io.solve import solve_problem
    from orientviz.io.problem import dumps_problem, loads_problem, problem_from_block

    b = sim.block.copy()
    k = int(np.flatnonzero(~np.isfinite(b.points.xyz_known).any(axis=1))[0])
    b.points.xyz[k] += 1e6
    assert f"point {b.points.ids[k]!r} lies up to" in _checks(b)["far-away"].message
    sol = solve_problem(loads_problem(dumps_problem(problem_from_block(b)), "f.json"), "bundle")
    far = [n for n in sol.notes if "far outside" in n]
    assert far and far[0].startswith(f"warning: in the file's values: point {b.points.ids[k]!r} lies")
