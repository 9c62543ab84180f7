"""Reproductions of the papers' numbers: ``orientviz reproduce NAME``.

Each entry of :data:`REGISTRY` names a module with a function ``table(*, paper=None,
**options) -> list[Row]`` and a function ``paper_values() -> dict[str, value]`` (the
stored table of the paper's printed values, keyed by :attr:`Row.key`; ``table(paper=…)``
reads a changed copy, so a test can perturb it and see the flags follow and nothing else
move). A row compares one number of a paper with orientviz's value for it, with a label
(predicted / fitted / illustrative) and a flag read from the paper's value
(:mod:`orientviz.reproduce.rows`); rows with no paper value (``paper=None``) show what
orientviz adds. Modules are imported lazily.
"""

from __future__ import annotations

import importlib
from typing import Any

from .rows import LABELS, Row, counts, counts_line, format_rows, match, printed

#: name → ("module", "function", one-line description)
REGISTRY: dict[str, tuple[str, str, str]] = {
    "dbat-sxb": (
        "orientviz.reproduce.dbat_sxb",
        "table",
        "Börlin & Grussenmeyer, DBAT: the aerial block sxb (5 images, weighted control, check points)",
    ),
    "dbat-camcal": (
        "orientviz.reproduce.dbat_camcal",
        "table",
        "Börlin & Grussenmeyer, DBAT: camera calibration (21 images, backward lens model)",
    ),
    "dbat-roma": (
        "orientviz.reproduce.dbat_roma",
        "table",
        "Börlin et al., DBAT: the ROMA bundle (60 images, no control, self-calibration)",
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


def paper_values(name: str) -> dict[str, Any]:
    """A fresh copy of the stored paper values of reproduction ``name`` (by row key)."""
    if name not in REGISTRY:
        raise KeyError(f"unknown reproduction {name!r}; available: {', '.join(sorted(REGISTRY))}")
    return importlib.import_module(REGISTRY[name][0]).paper_values()


__all__ = [
    "LABELS",
    "REGISTRY",
    "Row",
    "available",
    "counts",
    "counts_line",
    "format_rows",
    "match",
    "paper_values",
    "printed",
    "run",
]
