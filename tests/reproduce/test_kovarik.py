"""`orientviz reproduce kovarik`: runs, and shows the laws the paper states."""

from __future__ import annotations

import json

import numpy as np

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
