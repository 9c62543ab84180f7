"""`orientviz reproduce kovarik`: runs, and shows the laws the paper states."""

from __future__ import annotations

import json

import numpy as np
import pytest

from orientviz.cli import main
from orientviz.reproduce import kovarik


def test_table_runs_and_has_the_experiments():
    rows = kovarik.table(n_trials=3)
    tasks = {r.task for r in rows}
    assert {"relief", "wrong ordinate", "pre-orientation"} <= tasks
    assert all(r.orientviz is not None for r in rows)


def test_relief_law_and_tenfold_shrinkage():
    lo = kovarik.run_experiment("kovarik9", 0.06, n_trials=6)
    hi = kovarik.run_experiment("kovarik9", 0.30, n_trials=6)
    assert np.nanmean(hi["passes"]) > np.nanmean(lo["passes"])
    # first pass 100-150 c (minimal pre-orientation), second at least ~tenfold smaller
    for c in lo["corrections_c"]:
        assert c[0] > 80 and c[1] < c[0] / 8


def test_wrong_ordinate_law():
    right = kovarik.run_experiment("kovarik9", 0.10, n_trials=4)
    wrong = kovarik.run_experiment("kovarik9", 0.10, n_trials=4, k=1.0)
    assert np.nanmean(wrong["passes"]) > 2 * np.nanmean(right["passes"])


def test_cli_json(capsys):
    assert main(["reproduce", "kovarik", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert any(r["task"] == "wrong ordinate" for r in rows)


def test_table_states_what_reproduces_and_why():
    rows = kovarik.table(n_trials=3)
    summary = {r.case: r for r in rows if r.task == "summary"}
    assert set(summary) == {"reproduced", "not reproduced", "why"}
    flagged = [r for r in rows if r.note.startswith("reproduced:")]
    n_yes = sum(r.note.startswith("reproduced: yes") for r in flagged)
    assert summary["reproduced"].orientviz == f"{n_yes} rows"
    assert summary["not reproduced"].orientviz == f"{len(flagged) - n_yes} rows"
    assert "abs(y)/abs(z) = k" in summary["why"].note


def test_implied_contraction_inverts_the_pass_count():
    rho = kovarik.implied_contraction(4, start_c=125.0, tol_c=1.0)
    assert 125.0 * rho**3 == pytest.approx(1.0)
    assert kovarik.implied_contraction(6) > kovarik.implied_contraction(3)


def test_pass_contraction_grows_with_relief_and_vanishes_for_the_exact_formula():
    exact = kovarik.pass_contraction(0.15, "exact", n_trials=3)
    assert np.all(exact < 1e-9)
    lo = np.median(kovarik.pass_contraction(0.05, n_trials=6))
    hi = np.median(kovarik.pass_contraction(0.20, n_trials=6))
    assert 0 < lo < hi < 1
    # a pass really shrinks the (noise-free) error by about that factor once the
    # second-order terms have died out
    from orientviz.orientation.plotter import AnalogPlotter, config_with, true_pair

    rng = np.random.default_rng(1968)
    pair = true_pair(config_with(relief=0.20, sigma_by=0.0, sigma_z=0.0), rng=rng)
    p = AnalogPlotter(pair, "kovarik9")
    p.settings = pair.elements + np.array([0.0, 0.0, 1.0, -1.0, 1.0]) / 6366.2
    e0 = np.abs(p.error[2:]).max()
    p.run_pass("kovarik9")
    rho = kovarik.pass_contraction(0.20, n_trials=1, seed=1968)[0]
    assert np.abs(p.error[2:]).max() <= 1.5 * rho * e0


def test_pre_oriented_start_needs_two_passes():
    r = kovarik.run_experiment("kovarik9", 0.15, n_trials=4, start_c=(1.0, 2.0))
    assert np.all(r["passes"] == 2)
