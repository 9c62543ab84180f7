"""Containers and number formatting of the adjustment report.

:class:`Report` holds ordered :class:`Section` objects; a section holds key/value lines,
:class:`Table` objects of already formatted cells, the raw numbers behind them and the
names of its figures. :func:`fmt`, :func:`length_unit` and :func:`angle_unit` fix how
numbers and units appear in both the text and the HTML form.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..io.problem import LENGTH_UNITS
from ..units import RHO

#: Redundancy numbers below this mark an observation as (nearly) uncontrolled.
R_LOW: float = 0.1
#: Intersection angles below this (gon) are reported as weak.
SMALL_ANGLE_GON: float = 10.0
#: Images measured in fewer points than this are reported.
FEW_POINTS: int = 6
#: Images whose points cover less than this fraction of the format (convex hull) are reported.
POOR_COVERAGE: float = 0.25
#: A correlation matrix with a condition number above this is reported as near-singular.
NEAR_SINGULAR: float = 1e8
#: Tables list at most this many rows (worst first where a ranking exists).
MAX_ROWS: int = 200


# --------------------------------------------------------------------------- containers
@dataclass
class Table:
    """A table of formatted cells.

    Attributes
    ----------
    columns : list of str
        Column headings (units in brackets).
    rows : list of list of str
        Formatted cells, one list per row.
    title : str
        Heading above the table ("" for none).
    align : str
        One character per column, ``"l"`` or ``"r"``.
    marked : list of bool
        Rows to highlight (e.g. flagged residuals); empty = none.
    note : str
        A line under the table (e.g. "12 more rows not shown").
    """

    columns: list[str]
    rows: list[list[str]]
    title: str = ""
    align: str = ""
    marked: list[bool] = field(default_factory=list)
    note: str = ""

    def __post_init__(self) -> None:
        if not self.align:
            self.align = "l" + "r" * (len(self.columns) - 1)

    def as_dict(self) -> dict[str, Any]:
        return {
            "title": self.title,
            "columns": self.columns,
            "rows": self.rows,
            "marked": self.marked,
            "note": self.note,
        }


@dataclass
class Section:
    """One section of the report.

    Attributes
    ----------
    key : str
        Identifier (``"summary"``, ``"sigma0"``, …), also the HTML anchor.
    title : str
        Heading.
    items : list of (str, str)
        Key/value lines (label, formatted value).
    tables : list of Table
    text : list of str
        Free paragraphs (explanations, units).
    values : dict
        The raw numbers behind the section (floats, ints, arrays; internal or stated units).
    figures : list of str
        Names of the figures of :mod:`orientviz.plot.report_figures` for this section.
    """

    key: str
    title: str
    items: list[tuple[str, str]] = field(default_factory=list)
    tables: list[Table] = field(default_factory=list)
    text: list[str] = field(default_factory=list)
    values: dict[str, Any] = field(default_factory=dict)
    figures: list[str] = field(default_factory=list)


@dataclass
class Report:
    """The whole report: title, sections, warnings and the data of the figures.

    Attributes
    ----------
    title, subtitle : str
    sections : list of Section
    plot : dict
        Arrays for the figures (see :mod:`orientviz.plot.report_figures`), in m and the
        stated units.
    """

    title: str
    subtitle: str
    sections: list[Section]
    plot: dict[str, Any] = field(default_factory=dict)

    def section(self, key: str) -> Section | None:
        """The section called ``key``, or None if the report has none."""
        for s in self.sections:
            if s.key == key:
                return s
        return None

    @property
    def keys(self) -> list[str]:
        return [s.key for s in self.sections]

    @property
    def warnings(self) -> list[str]:
        s = self.section("warnings")
        return list(s.values.get("messages", [])) if s else []


# --------------------------------------------------------------------------- formatting
def fmt(value: float, digits: int = 3, width: int = 0) -> str:
    """A number with ``digits`` decimals, or a dash when it is not finite."""
    if value is None or not np.isfinite(value):
        return "—".rjust(width)
    return f"{value:{width}.{digits}f}"


def fmt_g(value: float, sig: int = 4) -> str:
    """A number with ``sig`` significant digits, or a dash."""
    if value is None or not np.isfinite(value):
        return "—"
    return f"{value:.{sig}g}"


def length_unit(sigmas_m: ArrayLike, file_unit: str = "m") -> tuple[str, float]:
    """``("mm", 1000)`` when every finite σ is below 1 m, else ``("m", 1)``.

    A file in feet (``file_unit`` ``"ft"`` or ``"us-ft"``) gets its own unit and factor
    (per m) instead: its lengths are labelled as the file gives them; a file in model
    units (``"model"``, a reconstruction's arbitrary scale) gets ``("model units", 1)``.
    """
    if file_unit in ("ft", "us-ft"):
        return file_unit, 1.0 / LENGTH_UNITS[file_unit]
    if file_unit == "model":  # an arbitrary scale: no mm or m to switch to
        return "model units", 1.0
    a = np.asarray(sigmas_m, float)
    a = a[np.isfinite(a)]
    return ("mm", 1000.0) if a.size == 0 or np.max(a) < 1.0 else ("m", 1.0)


def angle_unit(file_unit: str) -> tuple[str, float]:
    """Unit and factor (per rad) for angle σ: mgon, cc, arc seconds or mrad."""
    if file_unit == "gon":
        return "mgon", RHO["gon"] * 1000.0
    if file_unit in ("c", "cc"):
        return "cc", RHO["cc"]
    if file_unit == "deg":
        return "arcsec", RHO["deg"] * 3600.0
    return "mrad", 1000.0


def decimals(scale_unit: str) -> int:
    """Decimals for σ in ``scale_unit``: 1 for the small units (mm, mgon, …), 4 for model
    units (no smaller unit to switch to), else 3."""
    if scale_unit == "model units":
        return 4
    return 1 if scale_unit in ("mm", "mgon", "cc", "arcsec", "mrad", "µm") else 3
