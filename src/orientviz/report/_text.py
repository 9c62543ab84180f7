"""The adjustment report as plain text: numbered sections and fixed-width tables.

Lays out a :class:`~orientviz.report.Report` in the manner of a classic
aerotriangulation protocol (one column per quantity, units in the headings). No figures;
the content is the same as that of the HTML report.
"""

from __future__ import annotations

import textwrap

from ._document import Report, Section, Table

#: Width of the rules between sections.
WIDTH: int = 100


def format_table(table: Table, indent: int = 2) -> list[str]:
    """A table as lines of fixed width (columns padded to their widest cell).

    Parameters
    ----------
    table : Table
        Formatted cells; ``align`` gives ``"l"`` or ``"r"`` per column.
    indent : int
        Spaces before every line.

    Returns
    -------
    list of str
    """
    cols = len(table.columns)
    rows = [[str(c) for c in r] + [""] * (cols - len(r)) for r in table.rows]
    widths = [max([len(table.columns[j])] + [len(r[j]) for r in rows]) for j in range(cols)]
    align = (table.align + "l" * cols)[:cols]

    def line(cells: list[str]) -> str:
        out = []
        for j, c in enumerate(cells):
            out.append(c.rjust(widths[j]) if align[j] == "r" else c.ljust(widths[j]))
        return (" " * indent + "  ".join(out)).rstrip()

    pad = " " * indent
    lines = []
    if table.title:
        lines.append(pad + table.title + ":")
    lines.append(line(table.columns))
    lines.append((pad + "  ".join("-" * w for w in widths)).rstrip())
    marked = table.marked or [False] * len(rows)
    for r, m in zip(rows, marked):
        lines.append(line(r) + ("  <==" if m else ""))
    if not rows:
        lines.append(pad + "(none)")
    if table.note:
        lines.append(pad + table.note)
    return lines


def format_section(section: Section, number: int) -> list[str]:
    """One numbered section: heading, key/value lines, paragraphs, tables, figure names."""
    head = f"{number}. {section.title}"
    lines = [head, "-" * len(head)]
    if section.items:
        w = min(max(len(k) for k, _ in section.items) + 2, 56)
        for k, v in section.items:
            lines.append(f"  {(k + ' ').ljust(w, '.')} {v}")
    if section.key == "warnings":
        msgs = section.values.get("messages", [])
        for k, m in enumerate(msgs, 1):
            lines += textwrap.wrap(
                f"! {k}. {m}", WIDTH, initial_indent="  ", subsequent_indent="       "
            )
    for t in section.tables:
        lines.append("")
        lines += format_table(t)
    for p in section.text:
        lines.append("")
        lines += textwrap.wrap(p, WIDTH, initial_indent="  ", subsequent_indent="  ")
    return lines


def text_report(report: Report, version: str = "") -> str:
    """The whole report as text.

    Parameters
    ----------
    report : Report
        From :func:`~orientviz.report.build_report`.
    version : str
        Program version for the header ("" = none).

    Returns
    -------
    str
        Lines separated by ``\\n``, ending with a newline.
    """
    rule = "=" * WIDTH
    lines = [rule, f" {report.title}", f" {report.subtitle}"]
    if version:
        lines.append(f" orientviz {version}")
    lines.append(rule)
    warn = report.warnings
    sigma = report.section("sigma0")
    if sigma is not None:
        lines.append(
            f" σ0 a posteriori = {sigma.values['sigma0']:.4f}   r = {report.section('redundancy').values['r']}"
            f"   warnings: {len(warn)}"
        )
        lines.append(rule)
    for k, sec in enumerate(report.sections, 1):
        lines.append("")
        lines += format_section(sec, k)
    lines.append("")
    lines.append(rule)
    return "\n".join(lines) + "\n"
