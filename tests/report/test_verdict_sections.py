"""The verdict's sections equal the whole report's, and the coverage screen is exact.

:func:`orientviz.report._sections.verdict_sections` forms only the sections the verdict
reads (σ0 test, residuals, warnings); its content must be that of
:func:`orientviz.report.build_report` for the same solution, warnings in the same
order. :func:`orientviz.report._coverage.coverage_below` computes an image's convex hull
only where an inscribed octagon does not already clear the threshold, and without Qhull
where it can; its answer must equal ``image_coverage(block) < threshold`` for every image
and its values print as Qhull's.
"""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.io.solve import load_named, solve_problem
from orientviz.report import build_report
from orientviz.report._coverage import coverage_below
from orientviz.report._sections import verdict_sections
from orientviz.report._stats import image_coverage

KEYS = ("sigma0", "residuals", "warnings")


def _same_sections(full, lean) -> None:
    for key in KEYS:
        a, b = full.section(key), lean.section(key)
        assert a.items == b.items, key
        assert a.text == b.text, key
        assert repr(a.values) == repr(b.values), key
    assert [s.key for s in lean.sections] == list(KEYS)


def _solved(name: str, **options):
    p = load_named(name)
    p.options = dict(p.options, **options)
    with np.errstate(all="ignore"):
        return p, solve_problem(p)


@pytest.fixture(scope="module")
def strip():
    return _solved("block_strip")


@pytest.mark.parametrize("name", ["dbat_sxb", "resection_example", "pair_example"])
def test_verdict_sections_equal_the_reports(name):
    p, s = _solved(name)
    with np.errstate(all="ignore"):
        _same_sections(build_report(p, s), verdict_sections(p, s))


def test_not_converged_and_poor_coverage_warnings_are_the_reports(strip):
    p, s = _solved("block_strip", max_iter=1)
    assert not s.adjustment.converged
    # a format this large leaves about half the images below the coverage threshold
    cov = image_coverage(p.data)
    p.data.cameras.format_mm = p.data.cameras.format_mm * np.sqrt(np.median(cov) / 0.25)
    with np.errstate(all="ignore"):
        full, lean = build_report(p, s), verdict_sections(p, s)
    _same_sections(full, lean)
    warnings = lean.section("warnings").values["messages"]
    assert any("did not converge" in w for w in warnings)
    poor = next(w for w in warnings if "cover less than" in w)
    n_poor = int(poor.split()[0])
    assert 0 < n_poor < p.data.n_images


def _cloud_block(strip, rng, kinds):
    """The strip's block with each image's points replaced by a chosen point cloud."""
    blk = strip[0].data.copy()
    obs = blk.observations
    xy = obs.xy.copy()
    for i in range(blk.n_images):
        rows = np.flatnonzero(obs.image == i)
        kind = kinds[i % len(kinds)]
        n = rows.size
        if kind == "disc":
            ang, rad = rng.uniform(0, 2 * np.pi, n), rng.uniform(0, 1, n) ** 0.5
            pts = np.c_[np.cos(ang) * rad, np.sin(ang) * rad] * rng.uniform(20, 110)
        elif kind == "line":  # collinear: Qhull refuses it, the coverage is 0
            t = rng.uniform(-100, 100, n)
            pts = np.c_[t, 0.5 * t]
        elif kind == "two":  # fewer than 3 finite points
            pts = np.full((n, 2), np.nan)
            pts[:2] = rng.uniform(-100, 100, (2, 2))
        else:  # a thin sliver along the diagonal
            t = rng.uniform(-110, 110, n)
            pts = np.c_[t, t + rng.normal(0, 3, n)]
        xy[rows] = pts
    blk.observations.xy = xy
    return blk


def _mixed_block(strip, seed):
    """A block whose images' points are discs, slivers, lines and pairs (in an order the
    seed turns), and each image's coverage from its hull."""
    rng = np.random.default_rng(seed)
    kinds = ["disc", "disc", "sliver", "line", "two", "disc", "sliver"]
    blk = _cloud_block(strip, rng, kinds[seed % 3 :] + kinds[: seed % 3])
    return blk, image_coverage(blk)


@pytest.mark.parametrize("seed", [28, 29, 30])
def test_coverage_below_equals_the_hulls_verdict(strip, seed):
    blk, exact = _mixed_block(strip, seed)
    thresholds = [0.05, 0.25, 0.6, *exact[np.isfinite(exact) & (exact > 0)][:6]]
    for thr in thresholds:  # also each image's own coverage: not below it
        below, cov = coverage_below(blk, thr)
        np.testing.assert_array_equal(below, exact < thr)
        np.testing.assert_allclose(cov[below], exact[below], rtol=1e-12, atol=0)
        shown = [f"{100 * c:.3g}" for c in cov[below]]  # as the warning prints them
        assert shown == [f"{100 * c:.3g}" for c in exact[below]]
    # the screen computes hulls only where needed: at a low threshold the discs clear it
    below, cov = coverage_below(blk, 0.01)
    assert np.isnan(cov).sum() >= blk.n_images // 3


@pytest.mark.parametrize("seed", [28, 29, 30])
def test_coverage_below_gives_the_first_values_asked_for(strip, seed):
    blk, exact = _mixed_block(strip, seed)
    among = np.arange(blk.n_images) % 3 != 1
    for thr in (0.05, 0.25, 0.6):
        for first in (1, 3, 6):
            below, cov = coverage_below(blk, thr, first=first, among=among)
            np.testing.assert_array_equal(below, exact < thr)
            named = np.flatnonzero(below & among)[:first]
            np.testing.assert_allclose(cov[named], exact[named], rtol=1e-12, atol=0)
            assert [f"{100 * c:.3g}" for c in cov[named]] == [f"{100 * c:.3g}" for c in exact[named]]
    # the points' boxes put the discs below a high threshold without their hulls
    below, cov = coverage_below(blk, 0.6, first=0)
    np.testing.assert_array_equal(below, exact < 0.6)
    assert np.isnan(cov[below]).sum() >= 1
