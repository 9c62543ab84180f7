"""The simulated analog plotter: true pair, readings, passes, formulas, pre-orientation."""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.errors import InputError
from orientviz.orientation import plotter as pl
from orientviz.orientation.plotter import preorientation_error
from orientviz.orientation.preorient import round_formulas
from orientviz.units import RHO_C


def _plotter(seed=0, scheme="kovarik9", **cfg):
    rng = np.random.default_rng(seed)
    pair = pl.true_pair(pl.config_with(**cfg), rng=rng)
    return pl.AnalogPlotter(pair, scheme, rng=rng)


def test_true_pair_geometry_and_relief():
    rng = np.random.default_rng(1)
    cfg = pl.config_with(relief=0.15)
    pair = pl.true_pair(cfg, rng=rng)
    H = cfg.projection_distance
    assert H == pytest.approx(220.7 / 92.0 * 152.7)
    X, Y = np.meshgrid(
        np.linspace(0, cfg.model_base, 41), np.linspace(-1, 1, 41) * cfg.ordinate * cfg.scale
    )
    Z = pair.height(X, Y)
    # the terrain is normalised on this very grid: its range is the relief exactly
    assert (Z.max() - Z.min()) / H == pytest.approx(0.15, rel=1e-12)
    # first corrections of 100-150 c and 1-3 mm by construction
    assert np.all(
        (np.abs(pair.elements[2:]) * RHO_C >= 100) & (np.abs(pair.elements[2:]) * RHO_C <= 150)
    )
    scene = pair.scene(n_grid=5)
    assert scene["terrain"].shape == (25, 3) and scene["xy_left"].shape == (25, 2)
    np.testing.assert_allclose(scene["centres"][1], [cfg.model_base, *pair.elements[:2]])


def test_readings_vanish_at_the_truth():
    p = _plotter(2, sigma_by=0.0, sigma_z=0.0)
    p.settings = p.pair.elements.copy()
    r = p.read()
    assert np.abs(r.parallax).max() < 1e-10
    # z readings are the terrain heights (rays meet exactly on the terrain)
    X, Y, Z = p.scheme_points()
    np.testing.assert_allclose(r.z, Z, atol=1e-9)


def test_noise_needs_rng():
    pair = pl.true_pair(pl.PlotterConfig(), rng=np.random.default_rng(0))
    with pytest.raises(InputError, match="rng"):
        pl.AnalogPlotter(pair)


@pytest.mark.parametrize("formula", ["exact", "kovarik9", "flat", "preorient"])
def test_every_formula_converges_and_is_recorded(formula):
    p = _plotter(3, relief=0.1)
    run = p.orient(formula)
    assert run.converged
    assert len(p.history) == run.n_passes and [r.index for r in p.history] == list(
        range(1, run.n_passes + 1)
    )
    # the last pass is below the tolerance, the first one is the big one (100-150 c)
    c = run.corrections_c()
    assert c[-1] < 1.0 and c[0] > 80
    # after convergence the dials agree with the truth to the reading noise: 5 µm
    # readings give σ(φ) ≈ 0.22 c; 3 c is > 10 σ
    assert np.abs(p.error[2:]).max() * RHO_C < 3.0
    assert np.abs(p.error[:2]).max() < 0.2


def test_exact_linearisation_shrinks_corrections_at_least_tenfold():
    p = _plotter(4, relief=0.15, sigma_by=0.0, sigma_z=0.0)
    c = p.orient("exact", tol_c=1e-3, tol_mm=1e-5).corrections_c()
    assert np.all(c[1:] / c[:-1] < 0.1)


def test_more_relief_more_passes_for_kovarik_formula():
    # the law the paper states, seen over the same 8 random pairs
    def mean_passes(relief):
        out = []
        for seed in range(8):
            out.append(_plotter(seed, relief=relief).orient("kovarik9").n_passes)
        return np.mean(out)

    assert mean_passes(0.30) > mean_passes(0.05)


def test_wrong_ordinate_needs_more_passes():
    right, wrong = [], []
    for seed in range(5):
        right.append(_plotter(seed).orient("kovarik9").n_passes)
        wrong.append(_plotter(seed).orient("kovarik9", k=1.0).n_passes)
    assert np.mean(wrong) > 2 * np.mean(right)


def test_axes_mode_applies_rotations_about_model_axes():
    p = _plotter(5, sigma_by=0.0, sigma_z=0.0, apply="axes")
    from orientviz.rotation import matrix_from_opk, matrix_from_rotvec

    R0 = matrix_from_opk(*p.settings[2:], sequence="pok")
    d = np.array([0.0, 0.0, 0.01, -0.02, 0.015])
    p.settings[2:] = [0.02, 0.03, -0.01]
    R0 = matrix_from_opk(*p.settings[2:], sequence="pok")
    p.apply(d)
    np.testing.assert_allclose(
        matrix_from_opk(*p.settings[2:], sequence="pok"), matrix_from_rotvec(d[2:]) @ R0, atol=1e-14
    )


def test_kovarik_formula_needs_nine_points():
    p = _plotter(6, scheme="gruber6")
    with pytest.raises(InputError, match="9-point"):
        p.run_pass("kovarik9")
    with pytest.raises(InputError, match="unknown formula"):
        p.run_pass("magic")


def test_round_formulas_exact_for_their_own_constants():
    # build parallaxes from Kovarik's own equation with k = 110/152.7 and flat terrain;
    # Δφ and Δbz (whose constants belong to 110 mm) come out to the rounding of the
    # constants (20 vs 20.02, 0.7 vs 0.694): ≤ 1 %
    b, k, z = 220.7, 110 / 152.7, -366.0
    u = np.array([0, 1, 0, 1, 0, 1.0])
    v = np.array([0, 0, 1, 1, -1, -1.0])
    x, y = u * b, v * k * abs(z)
    e = np.array([0.0, 0.5, 0.0, 40 / RHO_C, 0.0])  # bz, φ only (Kovarik senses)
    p = e[0] + (y / z) * e[1] - (b - x) * (y / z) * e[3]
    w, f, bz = round_formulas(p, np.full(6, z))
    assert w == pytest.approx(0.0, abs=1e-9)
    assert f == pytest.approx(40, rel=0.01)
    assert bz == pytest.approx(0.5, rel=0.01)


def test_preorientation_error_grows_with_rotation():
    out = preorientation_error([10.0, 100.0, 400.0], element="phi")
    err = np.abs(out["round"][:, 1])
    assert err[0] < err[1] < err[2]
    # the exact linearisation is exact to first order: its error grows ~ quadratically
    ex = np.abs(out["exact"][:, 1])
    assert ex[2] / ex[1] > 8


def test_z_read_only_in_the_first_passes():
    p = _plotter(6, relief=0.15)
    run = p.orient("kovarik9", z_reads=2, tol_c=0.0, max_passes=4)
    z = [r.readings.z for r in run.passes]
    assert not np.array_equal(z[0], z[1])  # read again in the first repetition
    np.testing.assert_array_equal(z[2], z[1])  # then re-used
    np.testing.assert_array_equal(z[3], z[1])
    with pytest.raises(InputError, match="heights"):
        p.run_pass("kovarik9", z=np.zeros(3))
