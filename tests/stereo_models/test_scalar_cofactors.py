"""The cofactor blocks of the point coordinates by the banded selected inverse equal those
by solves with the columns of G (stereo_models.scalar_cofactors, both paths)."""

from __future__ import annotations

import numpy as np
import pytest

import orientviz as ov
import orientviz.stereo_models._normal as normal
from orientviz.stereo_models import scalar_cofactors


@pytest.fixture(scope="module")
def adjusted():
    s = ov.simulate_block(3, 8, rng=np.random.default_rng(5), extra=None)
    return s.block


@pytest.mark.parametrize("method", ["rigorous", "pat-m"])
def test_the_banded_path_equals_the_solves(adjusted, method, monkeypatch):
    """Independent models with precision (7 parameters per model rigorously; PAT-M's 4 + 3
    by turns): the reduced systems here are small, so the banded path is forced by a
    lower size limit; the solves' path by a zero band fraction."""
    captured = []
    solve = normal.solve_sparse

    def keep(*args, **kw):  # every linear solution the adjustment makes
        sol = solve(*args, **kw)
        captured.append(sol)
        return sol

    monkeypatch.setattr(normal, "solve_sparse", keep)
    ov.independent_models(adjusted, method=method, precision=True)
    monkeypatch.setattr(normal, "DENSE_LIMIT", 10)
    checked = 0
    for sol in captured:
        ns = sol.D.size
        groups = np.arange(ns - ns % 3).reshape(-1, 3)
        groups[::4, 1] = -1  # a coordinate that is not an unknown
        monkeypatch.setattr(normal, "BAND_FRACTION", 1.0)
        banded = normal._banded_cofactors(sol, groups, 7)
        assert banded is not None
        monkeypatch.setattr(normal, "BAND_FRACTION", 0.0)
        ref = scalar_cofactors(sol, groups)
        np.testing.assert_allclose(banded, ref, rtol=1e-9, atol=1e-12 * np.abs(ref).max())
        checked += 1
    assert checked >= 1


@pytest.mark.parametrize("law", ["planimetry", "height"])
def test_the_laws_banded_path_with_the_models_centres(law, monkeypatch):
    """Ebner's laws by the banded path (forced by a lower size limit; the band ordered
    across the strips from the models' centres when narrower than reverse Cuthill-McKee)
    equal the laws by the solves' path (zero band fraction): every point's σ."""
    calls = []
    band = normal._band_order

    def spy(graph, centres):
        calls.append(centres is not None)
        return band(graph, centres)

    monkeypatch.setattr(normal, "_band_order", spy)

    def run():
        if law == "planimetry":
            return ov.simulate.planimetric_precision(4, models_per_strip=7, control_spacing=2)
        return ov.simulate.height_precision(2, n_strips=3, models_per_strip=7)

    monkeypatch.setattr(normal, "DENSE_LIMIT", 10)
    monkeypatch.setattr(normal, "BAND_FRACTION", 1.0)
    banded = run()
    assert calls == [True]
    monkeypatch.setattr(normal, "BAND_FRACTION", 0.0)
    ref = run()
    np.testing.assert_allclose(banded.sd, ref.sd, rtol=1e-10)
    assert banded.mu == pytest.approx(ref.mu, rel=1e-12)


def test_normal_equations_without_a_solve():
    """solve=False: no corrections, the same cofactors and re-solves as with them; a
    singular system still raises, at its first solve."""
    rng = np.random.default_rng(2)
    nm, p, ns = 6, 3, 10
    rows_model = np.repeat(np.arange(nm), 8)
    J = rng.normal(size=(rows_model.size, p))
    scalar = rng.integers(0, ns, rows_model.size)
    w = rng.uniform(0.5, 2.0, rows_model.size)
    r = rng.normal(size=rows_model.size)
    prior = np.where(np.arange(ns) < 4, 4.0, 0.0)
    args = (rows_model, J, scalar, w, r, nm, ns)
    full = normal.solve_rows(*args, prior_w=prior, prior_e=np.zeros(ns))
    lazy = normal.solve_rows(*args, prior_w=prior, prior_e=np.zeros(ns), solve=False)
    assert lazy.dtheta is None and lazy.dX is None
    assert lazy.factor._factor is None  # not factored yet
    groups = np.arange(ns - 1).reshape(-1, 3)
    np.testing.assert_allclose(
        scalar_cofactors(lazy, groups), scalar_cofactors(full, groups), rtol=1e-12
    )
    dt, dX = lazy.resolve(r)
    np.testing.assert_allclose(dt.reshape(nm, p), full.dtheta, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(dX, full.dX, rtol=1e-10, atol=1e-12)
    J1 = J.copy()
    J1[:, 2] = J1[:, 1]  # two parameters of every model alike: S singular
    sing = normal.solve_rows(rows_model, J1, scalar, w, r, nm, ns, prior_w=prior,
                             prior_e=np.zeros(ns), solve=False)  # fmt: skip
    with pytest.raises(ov.errors.NotDeterminableError):
        scalar_cofactors(sing, groups)
