"""``orientviz reproduce ebner`` (Ackermann 1974 Bild 3/4 after Ebner).

The paper's printed claims are in ``ebner.PAPER``. Predicted rows: the height claim
(μ_z ≈ 0.1 ‰ h with chains every 4-5 bases) and the σ0 ratio 1.5 of §20; illustrative:
the bound μ_xy < 2σ0. :data:`MISSES` lists the predicted rows that do not reproduce.
"""

import json

import pytest

from orientviz import cli
from orientviz.reproduce import ebner, run


@pytest.fixture
def small(monkeypatch):
    monkeypatch.setattr(ebner, "STRIPS", (2, 3, 4))
    monkeypatch.setattr(ebner, "SPACINGS", (2, 4, 5))
    monkeypatch.setattr(ebner, "STRIPS_4", (4,))


#: Predicted rows that do not reproduce (key → reason; the book says the same).
MISSES = {
    "§20|sigma0 ratio": "orientviz's simulated blocks give 1.2-1.3, not the theoretical 1.5; "
    "the paper itself calls 1.5 'not yet clearly confirmed' empirically",
}


def test_rows_state_the_laws(small):
    rows = run("ebner", pipeline=False)
    plan = [r for r in rows if r.task == "Bild 3" and r.quantity == "μ_xy / σ0"]
    assert plan and all(r.label == "illustrative" and r.paper == "< 2" for r in plan)
    assert all(r.match for r in plan)  # the paper's bound μ_xy < 2σ0 holds in every block
    h = {
        r.case.split("=")[1].split("b")[0].strip(): r.orientviz
        for r in rows
        if r.task == "Bild 4" and r.quantity == "μ_z / σ0"
    }
    assert h["2"] < h["4"] < h["5"]  # height precision falls with the chain spacing
    claim = [r for r in rows if r.key == "Bild 4|mu_z permille h"]
    # "μz ≈ 0.1 ‰ of the flying height" at 4-5 bases: rounded to the printed digit, 0.1
    assert len(claim) == 2 and all(r.label == "predicted" and r.match for r in claim)
    assert all(f"{r.value:.1f}" == "0.1" for r in claim)


def test_cli_json(small, capsys, monkeypatch):
    monkeypatch.setattr(ebner, "_pipeline_rows", lambda rng: [])
    monkeypatch.setattr(ebner, "_sigma0_numbers", lambda rng: ([1.2], [15.0]))
    assert cli.main(["reproduce", "ebner", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert {"task", "case", "quantity", "paper", "orientviz", "note", "label", "match"} <= set(
        data[0]
    )


@pytest.mark.slow
def test_full_reproduction():
    rows = ebner.table()
    chain = [r for r in rows if r.task == "Bild 3 (whole chain)"]
    # predicted planimetric precision holds for the whole chain from image coordinates
    assert all(0.7 < r.orientviz < 1.4 for r in chain)
    pred = {r.key: r for r in rows if r.label == "predicted"}
    assert {k for k, r in pred.items() if r.match is False} == set(MISSES)
    ratio = pred["§20|sigma0 ratio"]
    # the paper prints 1.5 (one decimal): matched would mean 1.45 <= ratio < 1.55
    assert ratio.paper == "1.5" and ratio.match is (f"{ratio.value:.1f}" == "1.5")
