"""Every case of the hostile corpus (tests/hostile/cases.py) keeps the CLI's contract."""

from __future__ import annotations

import pytest

from .cases import CASES
from .harness import check_case


def test_corpus_is_large_and_covers_every_command():
    assert len(CASES) >= 100
    commands = {c.name.split("/")[0] for c in CASES}
    assert commands >= {"solve", "export", "view", "import-bal", "import-colmap", "reproduce"}
    assert len({c.name for c in CASES}) == len(CASES)


@pytest.mark.parametrize("case", CASES, ids=str)
def test_case(case, tmp_path):
    if case.name.startswith("view"):
        pytest.importorskip("viser")
    check_case(case, tmp_path / "work")
