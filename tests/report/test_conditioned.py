"""The screen of well-conditioned 3 × 3 correlation matrices before their eigenvalues.

:func:`orientviz.report._stats.conditioned_below` certifies, from two leading minors and
the Gershgorin bound, that a point's correlation matrix has a condition number below the
warning's limit; only the others go to ``eigvalsh``. A certified matrix must never be one
``eigvalsh`` would flag, and the near-singular warnings must be the same with and without
the screen.
"""

from __future__ import annotations

import numpy as np
import pytest

from orientviz.io.solve import load_named, solve_problem
from orientviz.report import _quality
from orientviz.report._sections import verdict_sections
from orientviz.report._stats import conditioned_below


def _correlations(rng, k: int, smallest: np.ndarray) -> np.ndarray:
    """k random 3 × 3 correlation matrices whose covariance has eigenvalues 1, u, s."""
    q, _ = np.linalg.qr(rng.standard_normal((k, 3, 3)))
    lam = np.stack([np.ones(k), rng.uniform(0.1, 1.0, k), smallest], axis=1)
    cov = q @ (lam[:, :, None] * q.transpose(0, 2, 1))
    d = np.sqrt(np.einsum("kii->ki", cov))
    c = cov / (d[:, :, None] * d[:, None, :])
    c[:, np.arange(3), np.arange(3)] = 1.0
    return c


def _flagged(c: np.ndarray, limit: float) -> np.ndarray:
    """The code's own test of a condition number from ``eigvalsh``."""
    with np.errstate(all="ignore"):
        ev = np.linalg.eigvalsh(c)
        cond = np.where(ev[:, 0] > 0, ev[:, -1] / np.where(ev[:, 0] > 0, ev[:, 0], 1.0), np.inf)
    return ~(cond <= limit)


@pytest.mark.parametrize("limit", [1e4, 1e6, 1e8])
def test_a_certified_matrix_is_never_one_eigvalsh_flags(limit):
    rng = np.random.default_rng(7)
    smallest = 10.0 ** rng.uniform(-13, 0, 20000)  # from hopeless to well conditioned
    c = _correlations(rng, smallest.size, smallest)
    sure = conditioned_below(c, limit)
    flagged = _flagged(c, limit)
    assert not np.any(sure & flagged)
    assert flagged.any() and sure.any()
    # the screen does its work: most matrices far inside the limit pass it
    ev = np.linalg.eigvalsh(c)
    easy = ev[:, -1] / ev[:, 0] < limit / 1000
    assert np.mean(sure[easy]) > 0.9


def test_indefinite_and_undefined_matrices_are_never_certified():
    c = np.repeat(np.eye(3)[None], 4, axis=0)
    c[0, 0, 1] = c[0, 1, 0] = 1.2  # |ρ| > 1: indefinite
    c[1, 0, 1] = c[1, 1, 0] = 0.9  # two strong correlations of opposite sign: det < 0
    c[1, 0, 2] = c[1, 2, 0] = 0.9
    c[1, 1, 2] = c[1, 2, 1] = -0.9
    c[2, 1, 2] = c[2, 2, 1] = np.nan
    c[3, 0, 1] = c[3, 1, 0] = 1.0  # singular
    assert not conditioned_below(c, 1e8).any()
    assert conditioned_below(np.eye(3)[None], 1e8).all()


@pytest.mark.parametrize("name", ["dbat_sxb", "block_strip"])
def test_the_near_singular_warnings_are_those_of_eigvalsh_on_every_block(name, monkeypatch):
    p = load_named(name)
    with np.errstate(all="ignore"):
        s = solve_problem(p)
    # a low limit makes many point blocks near-singular: both sides of the screen are met
    monkeypatch.setattr(_quality, "NEAR_SINGULAR", 3.0)
    with np.errstate(all="ignore"):
        screened = verdict_sections(p, s).section("warnings").values["messages"]
    monkeypatch.setattr(_quality, "conditioned_below", lambda c, limit: np.zeros(len(c), bool))
    with np.errstate(all="ignore"):
        every = verdict_sections(p, s).section("warnings").values["messages"]
    assert screened == every
    assert any(m.startswith("near-singular:") for m in every)
