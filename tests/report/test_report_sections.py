"""The content of the adjustment report (text form): sections, and numbers that are
recomputed here from the solution arrays instead of trusting the report code."""

from __future__ import annotations

import re
import subprocess
import sys

import numpy as np
import pytest

import orientviz as ov
from orientviz.block import CHECK, TIE
from orientviz.io.datasets import dataset_path, list_datasets
from orientviz.io.problem import problem_from_block
from orientviz.report import build_report, chi2_test, intersection_angles, text_report

BLOCK_SECTIONS = [
    "summary",
    "sigma0",
    "redundancy",
    "images",
    "points",
    "check",
    "residuals",
    "correlations",
    "warnings",
]


def solved(name: str):
    problem = ov.load_problem(dataset_path(name))
    return problem, ov.solve_problem(problem)


@pytest.fixture(scope="module")
def strip():
    problem, solution = solved("block_strip")
    report = build_report(problem, solution)
    return problem, solution, report, text_report(report)


def item(text: str, label: str) -> str:
    """The value of a key/value line ``  label ..... value`` of the text report."""
    m = re.search(rf"^  {re.escape(label)} \.*\s(.*)$", text, flags=re.M)
    assert m, f"no line {label!r} in the report"
    return m.group(1).strip()


def table_row(text: str, first_cell: str) -> list[str]:
    """The cells of the first table row starting with ``first_cell``."""
    m = re.search(rf"^  {re.escape(first_cell)}\s+(.*)$", text, flags=re.M)
    assert m, f"no table row {first_cell!r}"
    return m.group(1).split()


def independent_sigma0_and_r(problem, solution) -> tuple[float, int]:
    """σ0 and r of a bundle with fixed control, from residuals, σ and the block tables."""
    adj = solution.adjustment
    block: ov.Block = problem.data
    used = np.isfinite(adj.redundancy_numbers)  # rays of check points are not adjusted
    n_tie = int(np.sum(block.points.role == TIE))
    r = int(used.sum()) - (6 * block.n_images + 3 * n_tie)
    vtpv = float(np.sum((adj.residuals[used] / adj.sigma_obs[used]) ** 2))
    return float(np.sqrt(vtpv / r)), r


def independent_check_rms_mm(problem, solution) -> np.ndarray:
    block: ov.Block = problem.data
    chk = np.flatnonzero(block.points.role == CHECK)
    pos = {k: i for i, k in enumerate(solution.point_ids)}
    est = solution.xyz[[pos[block.points.ids[i]] for i in chk]]
    d = est - block.points.xyz_known[chk]
    return np.sqrt(np.mean(d**2, axis=0)) * 1000.0


def test_block_report_has_every_section(strip):
    _, _, report, text = strip
    assert report.keys == BLOCK_SECTIONS
    for sec in report.sections:
        assert sec.items or sec.tables, sec.key
        assert re.search(rf"^\d+\. {re.escape(sec.title)}$", text, flags=re.M), sec.title
    # per-image table: one row per image, with σ columns in stated units
    images = report.section("images")
    assert len(images.tables[1].rows) == problem_images(strip)
    assert "σω [mgon]" in images.tables[1].columns


def problem_images(strip) -> int:
    return strip[0].data.n_images


def test_sigma0_and_redundancy_equal_recomputed_values(strip):
    problem, solution, _, text = strip
    sigma0, r = independent_sigma0_and_r(problem, solution)
    assert int(item(text, "redundancy r")) == r
    assert float(item(text, "σ0 a posteriori (unit weight)")) == pytest.approx(sigma0, abs=5e-5)
    n = int(np.isfinite(solution.adjustment.redundancy_numbers).sum())
    assert int(item(text, "observations n").split()[0]) == n
    assert float(item(text, "mean redundancy number r/n")) == pytest.approx(r / n, abs=5e-4)


def test_sigma0_test_statistic_and_bounds(strip):
    problem, solution, _, text = strip
    sigma0, r = independent_sigma0_and_r(problem, solution)
    stats = pytest.importorskip("scipy.stats")
    assert float(item(text, "test statistic T = r · σ0² (a priori σ0 = 1)")) == pytest.approx(
        r * sigma0**2, abs=5e-4
    )
    lo, hi = (
        float(x)
        for x in re.findall(r"[\d.]+", item(text, f"χ²({r}) bounds at α = 0.05 (two-sided)"))
    )
    assert lo == pytest.approx(stats.chi2.ppf(0.025, r), abs=5e-4)
    assert hi == pytest.approx(stats.chi2.ppf(0.975, r), abs=5e-4)
    accepted = lo <= r * sigma0**2 <= hi
    assert item(text, "result").startswith("accepted" if accepted else "REJECTED")


def test_check_point_rms_equals_recomputed_value(strip):
    problem, solution, report, text = strip
    rms = independent_check_rms_mm(problem, solution)
    printed = [float(x) for x in table_row(text, "μ (r.m.s.)")]
    assert printed == pytest.approx(rms, abs=0.051)  # printed with 0.1 mm
    # and the bundle's own check-point computation agrees
    assert np.asarray(report.section("check").values["rms_m"]) * 1000 == pytest.approx(
        solution.adjustment.check_rms * 1000, abs=1e-6
    )


def test_largest_normalised_residual_is_the_injected_blunder():
    from orientviz.simulate import simulate_block

    clean = simulate_block(2, 6, rng=7, n_check=2).block
    rays = clean.rays_per_point()
    tie = np.flatnonzero((clean.points.role == TIE) & (rays >= 4))
    ray = int(np.flatnonzero(clean.observations.point == tie[0])[1])

    def blunder(xy, rng):
        xy = xy.copy()
        xy[ray, 0] += 0.06  # 12 σ in x of one ray
        return xy, np.array([ray])

    sim = simulate_block(2, 6, rng=7, n_check=2, gross=blunder)
    problem = problem_from_block(sim.block, name="blunder")
    solution = ov.solve_problem(problem)
    report = build_report(problem, solution)
    top = report.section("residuals").values["largest"][0]
    assert top["index"] == 2 * ray  # x of the corrupted ray (x/y interleaved)
    assert top["point"] == sim.block.points.ids[sim.block.observations.point[ray]]
    assert top["image"] == sim.block.images.ids[sim.block.observations.image[ray]]
    w = solution.adjustment.normalized_residuals
    assert abs(top["w"]) == pytest.approx(np.nanmax(np.abs(w)))
    assert top["flagged"]
    text = text_report(report)
    first = next(ln for ln in text.splitlines() if re.match(rf"^\s+{2 * ray}\s+\S+/", ln))
    assert first.rstrip().endswith("<==")
    assert any("|w| > 3.29" in m for m in report.warnings)


@pytest.mark.parametrize("name", ["resection_example", "similarity_example", "pair_example"])
def test_kind_without_check_points_omits_the_section(name):
    problem, solution = solved(name)
    report = build_report(problem, solution)
    assert "check" not in report.keys
    text = text_report(report)
    assert "Check-point statistics" not in text
    for key in ("summary", "sigma0", "redundancy", "residuals", "correlations", "warnings"):
        assert key in report.keys


@pytest.mark.parametrize("name", list_datasets())
def test_every_shipped_problem_gets_a_report(name):
    problem, solution = solved(name)
    report = build_report(problem, solution)
    text = text_report(report)
    for key in ("summary", "sigma0", "redundancy", "residuals", "correlations", "warnings"):
        assert report.section(key) is not None
        assert report.section(key).title in text
    if solution.parameters:
        assert report.section("parameters") is not None
    adj = solution.adjustment
    assert report.section("redundancy").values["r"] == adj.redundancy


def test_chi2_bounds_match_scipy():
    stats = pytest.importorskip("scipy.stats")
    for r in (1, 7, 120, 5000):
        t = chi2_test(1.0, r, alpha=0.01)
        assert t["lower"] == pytest.approx(stats.chi2.ppf(0.005, r), rel=1e-10)
        assert t["upper"] == pytest.approx(stats.chi2.ppf(0.995, r), rel=1e-10)
        assert t["accepted"]
    assert not chi2_test(2.0, 50)["accepted"]
    assert chi2_test(1.0, 0)["accepted"] is None


def test_intersection_angles_of_a_known_geometry():
    # two images 200 m apart at 1000 m over a point below their midpoint; a third point
    # seen by one image only has no angle
    block = ov.Block.from_arrays(
        camera_c=[150.0],
        image_camera=[0, 0],
        X0=[[-100.0, 0.0, 1000.0], [100.0, 0.0, 1000.0]],
        angles=np.zeros((2, 3)),
        xyz=[[0.0, 0.0, 0.0], [50.0, 0.0, 0.0]],
        obs_image=[0, 1, 0],
        obs_point=[0, 0, 1],
        obs_xy=[[15.0, 0.0], [-15.0, 0.0], [22.5, 0.0]],
    )
    ang = intersection_angles(block, block.images.X0, block.points.xyz)
    assert ang[0] == pytest.approx(2 * np.arctan(100.0 / 1000.0))
    assert np.isnan(ang[1])


def test_core_report_does_not_import_matplotlib(tmp_path):
    code = (
        "import sys\n"
        "from orientviz.io.problem import load_problem\n"
        "from orientviz.io.datasets import dataset_path\n"
        "from orientviz.io.solve import solve_problem\n"
        "import orientviz.report as h\n"
        "p = load_problem(dataset_path('block_strip'))\n"
        f"h.write_report(p, solve_problem(p), r'{tmp_path / 'r.txt'}')\n"
        "assert 'matplotlib' not in sys.modules, 'matplotlib imported'\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "r.txt").read_text(encoding="utf-8").count("Check-point statistics") == 1


@pytest.mark.parametrize(
    "options, expected",
    [
        ({"free": True}, "free network: minimum constraints (7 parameters held, named below)"),
        (
            {"free": True, "fix": ["s00_000", "s00_003:X0"]},
            "free network: s00_000, s00_003:X0 held at their given values",
        ),
    ],
)
def test_the_datum_row_of_a_free_network_names_no_control_points(options, expected):
    """`solve --free [--fix …] --report`: control points are tie points there, so the summary's
    datum row must not count them as the datum (it said 'control points (fixed): 4 fixed …')."""
    problem = ov.load_problem(dataset_path("block_strip"))
    problem.options.update(options)
    text = text_report(build_report(problem, ov.solve_problem(problem)))
    assert item(text, "datum") == expected
    assert "datum by minimum constraints" in text or "held at the given values" in text


def test_the_datum_row_names_the_held_images_of_a_model_without_control(tmp_path):
    """`solve model.json --fix A --fix B:X0 --report` on an imported model: the held images
    are the datum, not '0 fixed and 0 weighted' control coordinates."""
    from orientviz.cli import main
    from orientviz.io.colmap import write_colmap

    block = ov.simulate_block(1, 5, rng=7, control="full").block
    write_colmap(block, tmp_path / "sparse", pixel_size_mm=0.01)
    assert main(["import-colmap", str(tmp_path / "sparse"), "-o", str(tmp_path / "m.json")]) == 0
    problem = ov.load_problem(tmp_path / "m.json")
    a, b = list(problem.data.images.ids)[:2]
    problem.options["fix"] = [a, f"{b}:X0"]
    text = text_report(build_report(problem, ov.solve_problem(problem)))
    assert item(text, "datum") == f"{a}, {b}:X0 held at their given values"
