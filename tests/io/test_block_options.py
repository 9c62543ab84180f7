"""Solver options of block problems (issue #14 point 6): ``robust``/``robust_scale``,
``fix`` and ``free`` — in the problem file's ``options`` and on the command line."""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

import orientviz as ov
from orientviz.block import TIE
from orientviz.bundle.loop import RobustLoss
from orientviz.cli import main
from orientviz.io.datasets import resolve_name
from orientviz.io.problem import Units, problem_from_block


def _doc(name: str = "block_strip") -> dict:
    return json.loads(Path(resolve_name(name)).read_text())


def _write(tmp_path, doc, name="p.json") -> str:
    path = tmp_path / name
    path.write_text(json.dumps(doc))
    return str(path)


def _solve(path: str, **options):
    problem = ov.load_problem(path)
    problem.options = dict(problem.options, **options)
    return problem, ov.solve_problem(problem)


def _simulated(gross_mm: float = 0.0):
    """A simulated 2 × 5 block with 150 tie points; optionally a gross error of
    ``gross_mm`` on the first ray of a tie point seen in 4 images. Returns the problem
    and the (image, point) ids of that ray."""
    sim = ov.simulate_block(2, 5, rng=7, extra=20, control="perimeter")
    block = sim.block
    rays = block.rays_per_point()
    tie = int(np.flatnonzero((block.points.role == TIE) & (rays >= 4))[0])
    k = int(np.flatnonzero(block.observations.point == tie)[0])
    block.observations.xy[k, 0] += gross_mm
    problem = problem_from_block(block, units=Units("m", "gon", "mm"), options={"control": "fixed"})
    return problem, (block.images.ids[block.observations.image[k]], block.points.ids[tie])


def test_weight_factors():
    """w = ρ′(e²) of standardised misclosures e (scale 2): Huber 2/e beyond 2, Cauchy
    1/(1 + e²/4), soft-L1 1/√(1 + e²/4); ρ itself by its closed form at e = 10."""
    s = np.array([0.0, 1.0, 2.0, 10.0]) ** 2
    assert RobustLoss("huber", 2.0).weights(s) == pytest.approx([1, 1, 1, 0.2])
    assert RobustLoss("cauchy", 2.0).weights(s) == pytest.approx([1, 0.8, 0.5, 1 / 26])
    assert RobustLoss("soft_l1", 2.0).weights(s) == pytest.approx(1 / np.sqrt(1 + s / 4))
    rho = [RobustLoss(k, 2.0)(np.array([100.0]))[0][0] for k in ("huber", "cauchy", "soft_l1")]
    assert rho == pytest.approx([2 * 2 * 10 - 4, 4 * np.log(26), 8 * (np.sqrt(26) - 1)])


@pytest.mark.parametrize("loss", ["huber", "cauchy"])
def test_robust_bundle_resists_a_gross_error(loss):
    """0.1 mm = 20 σ on one ray: least squares moves the centres by ~0.5 m, the robust
    bundle stays within a quarter of that, and its note names the ray by image/point."""
    clean = ov.solve_problem(_simulated()[0])
    problem, (image, point) = _simulated(0.1)
    ls = ov.solve_problem(problem)
    problem.options = dict(problem.options, robust=loss)
    rob = ov.solve_problem(problem)
    d_ls = np.abs(ls.X0 - clean.X0).max()
    d_rob = np.abs(rob.X0 - clean.X0).max()
    assert d_rob < 0.25 * d_ls
    note = next(n for n in rob.notes if n.startswith(f"robust adjustment ({loss}"))
    assert f"{image}/{point} (w = " in note.split("weight < 0.5:")[1].split(",")[0]


def test_robust_scale_and_command_line_equal_the_file_options(tmp_path, capsys):
    doc = _doc("dbat_sxb")
    path = _write(tmp_path, doc)
    assert main(["solve", path, "--json", "--robust", "cauchy", "--robust-scale", "3"]) == 0
    cli = json.loads(capsys.readouterr().out)
    doc["options"] = dict(doc.get("options", {}), robust="cauchy", robust_scale=3)
    assert main(["solve", _write(tmp_path, doc, "f.json"), "--json"]) == 0
    file = json.loads(capsys.readouterr().out)
    assert cli["sigma0"] == file["sigma0"]
    assert "scale 3 σ" in " ".join(file["notes"])
    assert main(["solve", path, "--json", "--robust", "cauchy", "--robust-scale", "1"]) == 0
    assert json.loads(capsys.readouterr().out)["sigma0"] != file["sigma0"]


def test_free_network_residuals_do_not_depend_on_the_datum(tmp_path):
    path = str(resolve_name("block_strip"))
    problem, a = _solve(path, free=True)
    block = problem.data
    _, b = _solve(path, free=True, fix=[block.images.ids[-1], f"{block.images.ids[0]}:Y0"])
    assert a.adjustment.converged and b.adjustment.converged
    na = a.adjustment.obs_slices["image"]
    assert a.adjustment.residuals[na] == pytest.approx(b.adjustment.residuals[na], abs=1e-8)
    assert a.adjustment.sigma0 == pytest.approx(b.adjustment.sigma0, rel=1e-6)
    # redundancy of a free network: 2 per ray − (6 per image + 3 per point − 7)
    rays = block.rays_per_point()
    kept = rays >= 2
    n_rays = int(rays[kept].sum())
    assert a.counts()["redundancy"] == 2 * n_rays - (6 * block.n_images + 3 * int(kept.sum()) - 7)
    assert "minimum constraints" in " ".join(a.notes)


def test_fix_names_an_unknown_id_in_one_line(tmp_path, capsys):
    assert main(["solve", "block_strip", "--fix", "nowhere"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "nowhere" in err and "options.fix" in err
    assert main(["solve", "block_strip", "--fix", "s00_000:Q"]) == 2
    assert "unknown part" in capsys.readouterr().err


def test_robust_applies_to_the_bundle_only(capsys):
    assert main(["solve", "block_compact", "--method", "models", "--robust", "huber"]) == 2
    assert "bundle only" in capsys.readouterr().err


def test_too_little_control_names_the_datum_choices(tmp_path, capsys):
    """No approximations and two control points: the message lists the datum choices,
    and the free network then solves the same block."""
    doc = _doc("dbat_sxb")
    rays = Counter(o["point"] for o in doc["observations"])
    ctrl = [p for p in doc["points"] if p.get("role") == "control" and rays[p["id"]] >= 2]
    for p in ctrl[2:]:  # two of them stay (control seen once cannot be tie points)
        p["role"] = "tie"
        for k in ("X", "Y", "Z", "sigma"):
            p.pop(k, None)
    path = _write(tmp_path, doc)
    assert main(["solve", path]) == 3
    err = capsys.readouterr().err
    assert "--free" in err and "--fix" in err and "3" in err
    assert main(["solve", path, "--free"]) == 0


def test_observed_centres_carry_the_datum_of_computed_approximations(tmp_path, capsys):
    """No approximations, two control points, but GNSS-like observed centres (σ 0.5 m):
    the approximations are carried onto the observed centres and the bundle converges."""
    doc = _doc("dbat_sxb")
    rays = Counter(o["point"] for o in doc["observations"])
    ctrl = [p for p in doc["points"] if p.get("role") == "control" and rays[p["id"]] >= 2]
    for p in ctrl[2:]:
        p["role"] = "tie"
        for k in ("X", "Y", "Z", "sigma"):
            p.pop(k, None)
    # the centres DBAT printed for the five photos (its report), rounded to 0.1 m
    centres = {"8811": (999660.9, 112368.4, 1916.6), "8936": (1000062.2, 112625.5, 1916.4),
               "8937": (1000077.4, 112417.5, 1910.4), "8938": (1000094.1, 112202.9, 1907.0),
               "9111": (1000482.6, 112370.5, 1937.1)}  # fmt: skip
    for im in doc["images"]:
        im["X0_obs"], im["X0_obs_sigma"] = list(centres[im["id"]]), [0.5, 0.5, 0.5]
    path = _write(tmp_path, doc)
    assert main(["solve", path, "--json"]) == 0, capsys.readouterr().err
    out = json.loads(capsys.readouterr().out)
    for im in out["images"]:
        assert np.allclose([im["X0"], im["Y0"], im["Z0"]], centres[im["id"]], atol=2.0)
