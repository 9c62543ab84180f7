"""orientviz.report: what an adjustment tells its reader.

A solved problem file (:func:`orientviz.io.solve.solve_problem`) is a :class:`Solution`
(parameters with σ in the file's units, flagged observations, as text or JSON for
``orientviz solve``). :func:`build_report` turns it into a :class:`Report` of
:class:`Section` objects in the order of a classic aerotriangulation protocol (σ̂0
with its χ² test, redundancy, exterior orientation, point precision, check points,
largest normalised residuals, correlations, geometry warnings); :func:`text_report`
and :func:`html_report` lay it out, :func:`verdict` reads off the global test, flags and
warnings that ``orientviz solve`` prints too, :func:`write_report` writes either by the
file's suffix. :func:`image_table` and :func:`point_table` are the per-image and
per-point tables of a block adjustment (and their CSV files).

Nothing here imports matplotlib: the HTML figures come from
:mod:`orientviz.plot.report_figures`, imported only when figures are drawn.

Examples
--------
>>> from orientviz.io import load_dataset, solve_problem       # doctest: +SKIP
>>> from orientviz.report import write_report                  # doctest: +SKIP
>>> problem = load_dataset("block_strip")                      # doctest: +SKIP
>>> write_report(problem, solve_problem(problem), "at.html")   # doctest: +SKIP
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..faces import lazy_names

#: The face's names and the modules they live in, loaded on first use (``orientviz
#: solve`` needs the verdict, not the HTML writer or the CSV tables).
_FACE: dict[str, str] = {
    "Parameter": "..io.solution",
    "Solution": "..io.solution",
    "Report": "._document",
    "Section": "._document",
    "Table": "._document",
    "FORMATS": "._html",
    "html_report": "._html",
    "report_format": "._html",
    "write_report": "._html",
    "build_report": "._sections",
    "chi2_test": "._stats",
    "image_coverage": "._stats",
    "intersection_angles": "._stats",
    "ResultTable": "._tables",
    "adjusted_block": "._tables",
    "image_table": "._tables",
    "point_table": "._tables",
    "read_csv_table": "._tables",
    "text_report": "._text",
    "verdict": "._verdict",
}

__all__ = [
    "FORMATS",
    "Parameter",
    "Report",
    "ResultTable",
    "Section",
    "Solution",
    "Table",
    "adjusted_block",
    "build_report",
    "chi2_test",
    "html_report",
    "image_coverage",
    "image_table",
    "intersection_angles",
    "point_table",
    "read_csv_table",
    "report_format",
    "text_report",
    "verdict",
    "write_report",
]


__getattr__ = lazy_names(__name__, _FACE, globals())


def __dir__() -> list[str]:
    return list(__all__)


if TYPE_CHECKING:  # for type checkers and editors; nothing is imported at run time
    from ..io.solution import Parameter, Solution
    from ._document import Report, Section, Table
    from ._html import FORMATS, html_report, report_format, write_report
    from ._sections import build_report
    from ._stats import chi2_test, image_coverage, intersection_angles
    from ._tables import ResultTable, adjusted_block, image_table, point_table, read_csv_table
    from ._text import text_report
    from ._verdict import verdict
