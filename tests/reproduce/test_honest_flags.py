"""Every reproduction's flags read the paper's stored values — and nothing else does.

For each entry of the reproduce REGISTRY the stored paper table (``paper_values()``) is
perturbed in a copy, the table is recomputed with it, and

* every flagged row whose value was moved far away stops matching (a printed change
  "a → b" is turned round instead, and its flag must flip);
* every non-matching row whose value is replaced by orientviz's own number, as the paper
  would print it, starts matching (keys read by one flagged row only);
* nothing in the orientviz column (shown value and compared value) changes.

A new reproduction is covered automatically; give it cheap options in :data:`QUICK`.
"""

from __future__ import annotations

import math
import re

import pytest

from orientviz import reproduce
from orientviz.reproduce import REGISTRY, Row, paper_values
from orientviz.reproduce.rows import printed

#: Cheap options per reproduction (and module constants to shrink), for three runs each.
QUICK: dict[str, dict] = {
    "geier": {"draws": 0},
    "kovarik": {"n_trials": 3},
    "ebner": {},
    "selfcal": {},
}
SHRINK: dict[str, dict[str, tuple]] = {
    "ebner": {"STRIPS": (2, 3), "SPACINGS": (4, 5), "STRIPS_4": (4,)},
}
_NUM = re.compile(r"[+\-−]?\d+(?:\.\d+)?")


def _far(v):
    """The value moved far away from anything orientviz computes."""
    if isinstance(v, bool):
        raise TypeError(v)
    if isinstance(v, (int, float)):
        return v + 10**6
    text = str(v)
    if text.lower().startswith("no solution"):
        return "123456"
    if text.lstrip().startswith("<"):
        return "< -1000000"
    if text.lstrip().startswith(">"):
        return "> 1000000"
    if text.startswith("10^"):
        return "10^9"
    if m := re.fullmatch(r"\s*(\S+)\s*→\s*(\S+)\s*", text):  # a change: the other way
        a, b = m.groups()
        return f"{b} → {a}" if a != b else f"{a} → {float(a) * 10**6}"
    return _NUM.sub(
        lambda m: str(float(m.group(0).replace("−", "-")) + 10**6).rstrip("0").rstrip("."), text
    )


def _as_printed(v, value: float, decimals: int | None):
    """orientviz's value written the way the paper writes ``v`` (same digits)."""
    if isinstance(v, (int, float)):
        d = (
            decimals
            if decimals is not None
            else (0 if isinstance(v, int) else len(repr(float(v)).split(".")[1]))
        )
        return round(value, d)
    text = str(v)
    if text.lower().startswith("no solution"):
        return printed(value, 0)
    if "→" in text:  # a change: value is orientviz's ratio after/before
        return f"1 → {printed(value, 3)}"
    nums = _NUM.findall(text)
    d = max((len(n.split(".")[1]) if "." in n else 0) for n in nums) if nums else 2
    return printed(value, d)


def _ours(rows: list[Row]):
    def same(v):
        return "nan" if isinstance(v, float) and math.isnan(v) else v

    return [(r.task, r.case, r.quantity, same(r.orientviz), same(r.value)) for r in rows]


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(REGISTRY))
def test_flags_follow_the_stored_paper_values_and_nothing_else(name, monkeypatch):
    import importlib

    module = importlib.import_module(REGISTRY[name][0])
    for attr, value in SHRINK.get(name, {}).items():
        monkeypatch.setattr(module, attr, value)
    opts = QUICK.get(name, {})
    stored = paper_values(name)
    assert stored, f"{name}: no stored paper values"
    base = reproduce.run(name, paper=dict(stored), **opts)
    flagged = [r for r in base if r.match is not None]
    assert flagged, f"{name}: no flagged rows"
    for r in base:
        if r.paper is not None:
            assert r.key in stored, f"{name}: row {r.task}/{r.case}/{r.quantity} has no key"
            assert r.paper == stored[r.key], f"{name}: {r.key} not read from the table"

    far = {k: _far(v) for k, v in stored.items()}
    moved = reproduce.run(name, paper=far, **opts)
    assert _ours(moved) == _ours(base), f"{name}: the orientviz column depends on the paper"
    for r0, r in zip(base, moved, strict=True):
        if r.match is None:
            continue
        if "→" in str(r0.paper):  # a change turned the other way: the flag must flip
            assert r.match is not r0.match, f"{name}: {r.key} did not follow {r.paper!r}"
        else:
            assert r.match is False, f"{name}: {r.key} still matches {r.paper!r}"

    users: dict[str, int] = {}
    for r in flagged:
        users[r.key] = users.get(r.key, 0) + 1
    targets = {
        r.key: _as_printed(stored[r.key], r.value, r.decimals)
        for r in flagged
        if r.match is False and users[r.key] == 1 and r.value is not None
        and not (isinstance(r.value, float) and math.isnan(r.value))
    }  # fmt: skip
    if targets:
        near = dict(stored) | targets
        fixed = reproduce.run(name, paper=near, **opts)
        assert _ours(fixed) == _ours(base)
        now = {r.key: r.match for r in fixed if r.key in targets}
        assert all(now.values()), {k: (targets[k], m) for k, m in now.items() if not m}


def test_every_reproduction_has_the_two_functions():
    import importlib

    for name, (mod, func, _) in REGISTRY.items():
        m = importlib.import_module(mod)
        assert callable(getattr(m, func)) and callable(m.paper_values), name
        a, b = m.paper_values(), m.paper_values()
        assert a == b and a is not b, f"{name}: paper_values must return a fresh copy"


def test_rows_need_a_label_when_they_carry_a_paper_value():
    with pytest.raises(ValueError, match="needs a label"):
        Row("t", "c", "q", "0.32", 0.32)
    with pytest.raises(ValueError, match="must name the choices"):
        Row("t", "c", "q", "0.32", 0.32, label="fitted")
    assert Row("t", "c", "q", None, 1.0).match is None


@pytest.mark.parametrize(
    "paper, value, expected",
    [
        ("0.32", 0.3249, True), ("0.32", 0.3251, False), ("0.32", 0.3254, False),
        (0.32, 0.3150, True), (-2, -1.6, True), (-2, -2.6, False), ("0.00", -0.004, True),
        ("2-3", 3.4, True), ("2-3", 3.5, False), ("4", 3.0, False), ("5-6", 4.6, True),
        ("10-30", 8.1, False), ("10-30", 9.6, True),
        ("about 3", 2.86, True), ("about 3", 2.4, False), ("about 0.1", 0.112, True),
        ("10^-1", 0.06, True), ("10^-1", 0.02, False), ("10^-1", 0.4, False),
        ("< 2", 1.06, True), ("< 2", 2.0, False), ("1.5", 1.27, False),
        ("no solution", None, True), ("no solution (singular matrix)", 1.0, False),
    ],
)  # fmt: skip
def test_the_rules_read_the_printed_value(paper, value, expected):
    row = Row("t", "c", "q", paper, value, label="predicted", value=value,
              decimals=2 if isinstance(paper, float) else None)  # fmt: skip
    assert row.match is expected, row.rule


def test_the_command_prints_the_counts(capsys):
    from orientviz.cli import main

    assert main(["reproduce", "kovarik"]) == 0
    out = capsys.readouterr().out
    assert "counts: " in out and "(predicted)" in out and "(fitted: " in out
