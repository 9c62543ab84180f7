"""Reproductions of the papers' numbers: ``orientviz reproduce NAME``.

Each entry of :data:`REGISTRY` names a function ``table(**options) -> list[Row]``.
A row compares one number of a paper with orientviz's value for it; rows with no
paper value (``paper=None``) show what orientviz adds. Modules are imported lazily.
"""

from __future__ import annotations

import importlib
from dataclasses import asdict, dataclass
from typing import Any

#: name → ("module", "function", one-line description)
REGISTRY: dict[str, tuple[str, str, str]] = {
    "dbat-sxb": (
        "orientviz.reproduce.dbat_sxb",
        "table",
        "Börlin & Grussenmeyer, DBAT: the aerial block sxb (5 images, weighted control, check points)",
    ),
    "ebner": (
        "orientviz.reproduce.ebner",
        "table",
        "Ackermann 1974 Bild 3/4 after Ebner: block precision vs strips and height-chain spacing",
    ),
    "geier": (
        "orientviz.reproduce.geier",
        "table",
        "Geier 1973 Fig. 8: radar panorama orientation tasks on ten surfaces",
    ),
    "kovarik": (
        "orientviz.reproduce.kovarik",
        "table",
        "Kovarik 1968: passes of numerical relative orientation vs relief, wrong ordinate",
    ),
    "selfcal": (
        "orientviz.reproduce.selfcal",
        "table",
        "Ackermann 1974 Tables 3-5: bundle blocks without/with self-calibration",
    ),
}


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
        orientviz's value.
    note : str
        Why it differs, or how it was obtained.
    """

    task: str
    case: str
    quantity: str
    paper: Any
    orientviz: Any
    note: str = ""

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def available() -> dict[str, str]:
    """Names of the reproductions with their descriptions."""
    return {k: v[2] for k, v in sorted(REGISTRY.items())}


def run(name: str, **options: Any) -> list[Row]:
    """Run reproduction ``name`` and return its rows."""
    if name not in REGISTRY:
        known = ", ".join(sorted(REGISTRY)) or "none yet"
        raise KeyError(f"unknown reproduction {name!r}; available: {known}")
    module, func, _ = REGISTRY[name]
    return getattr(importlib.import_module(module), func)(**options)


def format_rows(rows: list[Row]) -> str:
    """Plain-text table of rows for the terminal."""

    def fmt(v: Any) -> str:
        if v is None:
            return "—"
        if isinstance(v, float):
            return f"{v:.6g}"
        return str(v)

    header = ("task", "case", "quantity", "paper", "orientviz", "note")
    cells = [header] + [
        (r.task, r.case, r.quantity, fmt(r.paper), fmt(r.orientviz), r.note) for r in rows
    ]
    widths = [max(len(c[i]) for c in cells) for i in range(5)]
    lines = []
    for k, c in enumerate(cells):
        lines.append(
            "  ".join(c[i].ljust(widths[i]) for i in range(5)) + ("  " + c[5] if c[5] else "")
        )
        if k == 0:
            lines.append("  ".join("-" * w for w in widths))
    return "\n".join(lines)
