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
