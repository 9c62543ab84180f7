"""Rows of a reproduction: one paper number beside orientviz's, with its label and flag.

Every reproduction (``orientviz reproduce NAME``) returns a list of :class:`Row`. The
rules that hold for all of them:

* **Label** — how orientviz's number was obtained:

  - ``"predicted"``: computed from the paper's inputs and stated conventions only;
  - ``"fitted"``: a convention or setting the paper does not state was chosen by
    matching this number or its column (:attr:`Row.fitted` names the choices);
  - ``"illustrative"``: the paper gives a pattern or a claim, not a number to recompute.

  Rows with no paper value (``paper=None``) show what orientviz adds; they have no
  label and no flag and are not counted.
* **Flag** (:attr:`Row.match`) — read from the paper's value as printed, by one of the
  rules of :func:`match` (the rule's text is :attr:`Row.rule`): a printed number is met
  when orientviz's value rounded to the printed digits equals it; a printed range
  ``"a-b"`` when the rounded value lies in it; ``"about X"`` when the value rounded to
  X's digits is X; ``"10^n"`` (a power of ten, "um eine Zehner-Potenz") when the value
  rounded in log10 is n; ``"a → b"`` (a pattern: a change) when orientviz's ratio
  after/before goes the same way; ``"< X"`` / ``"> X"`` when the paper's own inequality holds.
  No window is fixed in the code: change the paper's value and the flag follows.
* **Counts** — :func:`counts` groups the flagged rows by :attr:`Row.group` and label,
  e.g. ``"calibration 60/60 (fitted: rotation order, surface depth, stopping rule)"``.
"""

from __future__ import annotations

import math
import re
from dataclasses import asdict, dataclass, field
from typing import Any

#: The three labels (see the module docstring).
LABELS: tuple[str, ...] = ("predicted", "fitted", "illustrative")

_NUM = r"[+\-−]?\d+(?:\.\d+)?"


def _num(text: str) -> tuple[float, int]:
    """A printed number and its number of decimals ("−0.30" → (-0.3, 2))."""
    t = text.strip().replace("−", "-").replace(",", ".")
    dec = len(t.split(".")[1]) if "." in t else 0
    return float(t), dec


def printed(value: float, decimals: int) -> str:
    """A number as printed with ``decimals`` digits ("-0.00" shown as "0.00")."""
    s = f"{value:.{decimals}f}"
    return s[1:] if s.startswith("-") and float(s) == 0 else s


def match(paper: Any, value: Any, decimals: int | None = None) -> tuple[bool | None, str]:
    """Whether ``value`` reproduces the printed ``paper`` value, and the rule used.

    Parameters
    ----------
    paper : str, float or None
        The paper's value as printed: a number (``"0.32"``, ``-2``; with ``decimals`` if
        given as a float), a range ``"2-3"``, ``"about 3"``, a power of ten ``"10^-1"``,
        a change ``"5.7 → 3.4"`` (``value`` is then orientviz's ratio after/before),
        an inequality ``"< 2"``, or ``"no solution"`` (matched when orientviz has
        none either). Text after ``" ("`` is a comment.
    value : float
        orientviz's unrounded value (same unit as the paper's).
    decimals : int, optional
        Digits printed by the paper when ``paper`` is a float (default: as in its repr).

    Returns
    -------
    (bool or None, str)
        The flag (None when nothing can be compared) and the rule, in words.
    """
    if paper is None:
        return None, ""
    if isinstance(paper, str) and paper.lower().startswith("no solution"):
        ok = value is None or (isinstance(value, float) and not math.isfinite(value))
        return ok, "the paper has no solution: matched when orientviz has none either"
    if value is None:
        return None, ""
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None, ""
    if not math.isfinite(v):
        return False, "orientviz has no finite value"
    if isinstance(paper, (int, float)) and not isinstance(paper, bool):
        d = decimals if decimals is not None else _num(repr(float(paper)))[1]
        if isinstance(paper, int):
            d = 0 if decimals is None else decimals
        return printed(v, d) == printed(float(paper), d), f"rounded to {d} decimals equals"
    text = str(paper).split(" (")[0].strip()
    if m := re.fullmatch(_NUM, text):
        p, d = _num(text)
        return printed(v, d) == printed(p, d), f"rounded to {d} decimals equals"
    if m := re.fullmatch(rf"({_NUM})\s*[-–]\s*({_NUM})", text):
        (a, da), (b, db) = _num(m.group(1)), _num(m.group(2))
        d = max(da, db)
        r = float(printed(v, d))
        return a <= r <= b, f"rounded to {d} decimals lies in [{m.group(1)}, {m.group(2)}]"
    if m := re.fullmatch(rf"(?:about|≈)\s*({_NUM})", text):
        p, d = _num(m.group(1))
        return printed(v, d) == printed(p, d), f"about: rounded to {d} decimals equals"
    if m := re.fullmatch(r"10\^\s*([+\-−]?\d+)", text):
        n = int(m.group(1).replace("−", "-"))
        ok = v > 0 and round(math.log10(v)) == n
        return ok, f"power of ten: round(log10) equals {n}"
    if m := re.fullmatch(rf"({_NUM})\s*(?:→|->)\s*({_NUM})", text):
        (p0, _), (p1, d1) = _num(m.group(1)), _num(m.group(2))
        if p1 == p0:
            ok = printed(p0 * v, d1) == printed(p0, d1)
            return ok, "the paper's value is unchanged: orientviz's ratio keeps it at its digits"
        ok = (v < 1.0) if p1 < p0 else (v > 1.0)
        way = "falls" if p1 < p0 else "rises"
        return ok, f"direction: the paper's value {way}; orientviz's ratio after/before agrees"
    if m := re.fullmatch(rf"([<>])\s*({_NUM})", text):
        p, _ = _num(m.group(2))
        ok = v < p if m.group(1) == "<" else v > p
        return ok, f"the paper's inequality {m.group(1)} {m.group(2)} holds"
    return None, "no rule reads this paper value"


@dataclass
class Row:
    """One compared number.

    Attributes
    ----------
    task : str
        The paper's task or table, e.g. ``"calibration"``, ``"Table 3"``.
    case : str
        The column / configuration, e.g. ``"plane"``, ``"relief 10 %"``.
    quantity : str
        What is compared, with its unit, e.g. ``"m0 [m]"``.
    paper : float, str or None
        The paper's value as printed (None if the paper gives none).
    orientviz : float, str or None
        orientviz's value as shown (rounded, or a short text).
    note : str
        Why it differs, or how it was obtained.
    label : str or None
        ``"predicted"``, ``"fitted"`` or ``"illustrative"`` (:data:`LABELS`); None for a
        row without a paper value.
    value : float or None
        The number the flag compares (unrounded; default: ``orientviz`` if numeric).
    decimals : int or None
        Digits the paper prints, when ``paper`` is given as a float.
    fitted : tuple of str
        For ``label="fitted"``: the choices fitted on this number or its column.
    group : str
        The counting group (default: ``task``).
    key : str
        Where ``paper`` comes from: its key in the reproduction's stored table
        (``paper_values()``); empty for rows without a paper value.
    match : bool or None
        Set from ``paper`` and ``value`` by :func:`match` (None: not compared).
    rule : str
        The rule that set ``match``, in words.
    """

    task: str
    case: str
    quantity: str
    paper: Any
    orientviz: Any
    note: str = ""
    label: str | None = None
    value: float | None = None
    decimals: int | None = None
    fitted: tuple[str, ...] = ()
    group: str = ""
    key: str = ""
    match: bool | None = field(default=None, init=False)
    rule: str = field(default="", init=False)

    def __post_init__(self) -> None:
        if self.paper is not None and self.label not in LABELS:
            raise ValueError(
                f"row {self.task}/{self.case}/{self.quantity}: a row with a paper value "
                f"needs a label in {LABELS}, got {self.label!r}"
            )
        if self.label == "fitted" and not self.fitted:
            raise ValueError(f"row {self.task}/{self.case}: 'fitted' must name the choices")
        self.group = self.group or self.task
        v = self.value
        if v is None and isinstance(self.orientviz, (int, float)):
            v = self.orientviz
        self.match, self.rule = match(self.paper, v, self.decimals)

    def as_dict(self) -> dict[str, Any]:
        """The row as a JSON-ready dict (with ``label``, ``match`` and ``rule``)."""
        d = asdict(self)
        d["fitted"] = list(self.fitted)
        return d


def counts(rows: list[Row]) -> list[tuple[str, str, int, int, tuple[str, ...]]]:
    """Matches per group and label: ``(group, label, matched, compared, fitted choices)``.

    Only rows with a flag (``match`` not None) count; groups keep their first order.
    """
    acc: dict[tuple[str, str], list] = {}
    for r in rows:
        if r.match is None or r.label is None:
            continue
        e = acc.setdefault((r.group, r.label), [0, 0, []])
        e[0] += bool(r.match)
        e[1] += 1
        for f in r.fitted:
            if f not in e[2]:
                e[2].append(f)
    return [(g, lab, k, n, tuple(f)) for (g, lab), (k, n, f) in acc.items()]


def counts_line(rows: list[Row]) -> str:
    """One line of counts, e.g. ``"calibration 60/60 (fitted: rotation order, …), …"``."""
    parts = []
    order = {"fitted": 0, "predicted": 1, "illustrative": 2}
    for g, lab, k, n, fit in sorted(counts(rows), key=lambda c: order[c[1]]):
        what = f"fitted: {', '.join(fit)}" if lab == "fitted" else lab
        parts.append(f"{g} {k}/{n} ({what})")
    return ", ".join(parts) if parts else "no flagged rows"


def format_rows(rows: list[Row], width: int | None = None) -> str:
    """Plain-text table of rows for the terminal, with the counts line at the end.

    Parameters
    ----------
    rows : list of Row
    width : int, optional
        Widest line allowed (characters). A table wider than this is laid out as one
        block per task and case instead: the quantity, then paper · orientviz · label ·
        match, then the note, each wrapped to ``width``. None: always the one-line-per-row
        table (``orientviz reproduce --wide``).
    """

    def fmt(v: Any) -> str:
        if v is None:
            return "—"
        if isinstance(v, float):
            return f"{v:.6g}"
        return str(v)

    def flag(r: Row) -> str:
        return "—" if r.match is None else ("yes" if r.match else "no")

    header = ("task", "case", "quantity", "paper", "orientviz", "label", "match", "note")

    def digits(r: Row, v: Any) -> str:
        if r.decimals is not None and isinstance(v, (int, float)):
            return printed(float(v), r.decimals)  # as printed: 0.30, not 0.3
        return fmt(v)

    cells = [header] + [
        (r.task, r.case, r.quantity, digits(r, r.paper), digits(r, r.orientviz), r.label or "—", flag(r),
         r.note)
        for r in rows
    ]  # fmt: skip
    nw = len(header) - 1
    widths = [max(len(c[i]) for c in cells) for i in range(nw)]
    lines = []
    for k, c in enumerate(cells):
        lines.append(
            "  ".join(c[i].ljust(widths[i]) for i in range(nw)) + ("  " + c[nw] if c[nw] else "")
        )
        if k == 0:
            lines.append("  ".join("-" * w for w in widths))
    counts_text = "counts: " + counts_line(rows)
    if width is not None and max(len(line) for line in [*lines, counts_text]) > width:
        import textwrap

        lines = _blocks(cells[1:], width)
        counts_text = textwrap.fill(counts_text, width, subsequent_indent="  ")
    lines.append("")
    lines.append(counts_text)
    return "\n".join(lines)


def _blocks(cells: list[tuple[str, ...]], width: int) -> list[str]:
    """The rows of :func:`format_rows` as blocks per task and case, wrapped to ``width``."""
    import textwrap

    def wrap(text: str, indent: str) -> list[str]:
        return textwrap.wrap(text, width, initial_indent=indent, subsequent_indent=indent + "  ",
                             break_long_words=True, break_on_hyphens=False) or [indent]  # fmt: skip

    lines: list[str] = []
    group = None
    for task, case, quantity, paper, ours, label, flag, note in cells:
        if (task, case) != group:
            group = (task, case)
            lines += ([""] if lines else []) + wrap(f"{task} — {case}", "")
        lines += wrap(quantity, "  ")
        lines += wrap(f"paper {paper} · orientviz {ours} · {label} · match {flag}", "      ")
        if note:
            lines += wrap(note, "      ")
    return lines
