"""The checkers of lesson 08 pass their solutions and reject every mutant."""

import pytest

from orientviz.exercises import lesson08 as L

CASES = [(c, name, fn) for c, ms in L.MUTANTS.items() for name, fn in ms.items()]


@pytest.mark.parametrize("check", sorted(L.SOLUTIONS))
def test_solution_passes(check, capsys):
    getattr(L, check)(L.SOLUTIONS[check])
    assert capsys.readouterr().out.startswith("✓")


@pytest.mark.parametrize("check,name,fn", CASES, ids=[f"{c}-{n}" for c, n, _ in CASES])
def test_mutant_rejected(check, name, fn):
    with pytest.raises(AssertionError):
        getattr(L, check)(fn)


@pytest.mark.parametrize("check", sorted(L.SOLUTIONS))
def test_blank_says_not_written(check):
    def blank(*args):
        raise NotImplementedError

    with pytest.raises(AssertionError, match="not written yet"):
        getattr(L, check)(blank)
