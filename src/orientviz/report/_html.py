"""The adjustment report as one self-contained HTML file, and :func:`write_report`.

The HTML has its CSS inline and its figures as base64 PNG ``data:`` images: no
scripts, no external URLs, so it can be mailed or archived as it is. Every text is
HTML-escaped. matplotlib is imported only when figures are requested; without it the
report is written without figures and says so.

:func:`write_report` is the one entry point for programs and lessons: it builds the
sections (:mod:`orientviz.report._sections`) and writes HTML or plain text
(:mod:`orientviz.report._text`) by the suffix of the path.
"""

from __future__ import annotations

import base64
import html
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..io.jsonio import write_atomic
from ..io.problem import Problem
from ..io.solution import Solution
from ..version import __version__
from ._document import Report, Section, Table
from ._sections import build_report
from ._text import text_report

#: Suffixes :func:`write_report` understands.
FORMATS: dict[str, str] = {".html": "html", ".htm": "html", ".txt": "text"}

CSS = """
:root{--ink:#1d2733;--muted:#5d6b7a;--line:#d9dee4;--head:#1f4e79;--bg:#f5f7f9;--warn:#a04000;
--bad:#b03a2e;--ok:#1e8449}
*{box-sizing:border-box}
body{margin:0;font:14px/1.45 -apple-system,"Segoe UI",Helvetica,Arial,sans-serif;color:var(--ink);
background:#fff}
.page{max-width:1180px;margin:0 auto;padding:28px 32px 48px}
header{border-bottom:3px solid var(--head);padding-bottom:12px;margin-bottom:18px}
header h1{margin:0;font-size:24px;color:var(--head);font-weight:600}
header .sub{color:var(--muted);margin-top:4px;word-break:break-all}
.cards{display:flex;flex-wrap:wrap;gap:10px;margin:16px 0 8px}
.card{flex:1 1 150px;border:1px solid var(--line);border-radius:6px;padding:8px 12px;background:var(--bg)}
.card .k{font-size:12px;color:var(--muted)}
.card .v{font-size:20px;font-weight:600;margin-top:2px;font-variant-numeric:tabular-nums}
.card .n{font-size:12px;color:var(--muted)}
.card.bad .v{color:var(--bad)} .card.ok .v{color:var(--ok)}
nav{font-size:13px;margin:10px 0 4px;color:var(--muted)}
nav a{color:var(--head);text-decoration:none;margin-right:14px;white-space:nowrap}
section{margin-top:26px}
h2{font-size:18px;color:var(--head);border-bottom:1px solid var(--line);padding-bottom:4px;margin:0 0 10px}
h2 .no{color:var(--muted);font-weight:400;margin-right:6px}
h3{font-size:13px;margin:14px 0 6px;color:var(--ink);font-weight:600}
table.kv{border-collapse:collapse;margin:4px 0}
table.kv th{text-align:left;font-weight:400;color:var(--muted);padding:2px 18px 2px 0;vertical-align:top;
white-space:nowrap}
table.kv td{padding:2px 0;font-variant-numeric:tabular-nums}
.scroll{overflow-x:auto;max-width:100%}
table.data{border-collapse:collapse;font-size:12.5px;font-variant-numeric:tabular-nums;margin:2px 0 4px}
table.data th{background:var(--head);color:#fff;font-weight:500;padding:4px 9px;white-space:nowrap}
table.data td{padding:3px 9px;border-bottom:1px solid var(--line);white-space:nowrap}
table.data tr:nth-child(even) td{background:var(--bg)}
table.data td.r{text-align:right;font-family:"DejaVu Sans Mono",Menlo,Consolas,monospace;font-size:12px}
table.data td.c{text-align:center}
table.data tr.mark td{background:#fdebd0;color:var(--bad);font-weight:600}
.note{color:var(--muted);font-size:12px;margin:2px 0 8px}
p.text{color:var(--muted);font-size:13px;max-width:900px}
figure{margin:14px 0;text-align:center}
figure img{max-width:100%;height:auto;border:1px solid var(--line);border-radius:4px}
figcaption{font-size:12px;color:var(--muted);margin-top:4px}
ul.warn{list-style:none;padding:0;margin:6px 0}
ul.warn li{border-left:4px solid var(--warn);background:#fef5e7;padding:6px 10px;margin:6px 0;
border-radius:0 4px 4px 0}
.none{color:var(--ok)}
footer{margin-top:36px;border-top:1px solid var(--line);padding-top:8px;color:var(--muted);font-size:12px}
@media print{.page{max-width:none;padding:0}section{break-inside:avoid-page}}
"""

#: Captions of the figures.
CAPTIONS = {
    "overview": "Image footprints on the mean terrain height, projection centres, tie, control "
    "and check points; arrows: planimetric differences at the check points (exaggerated, "
    "see the scale arrow).",
    "image_sigma": "A-posteriori standard deviations of the exterior orientation per image.",
    "point_precision": "A-posteriori standard deviations of the estimated points.",
    "w_histogram": "Normalised residuals of all adjusted observations, the critical value "
    "(dashed) and the standard normal density expected without gross errors.",
}


def _e(text: Any) -> str:
    return html.escape(str(text), quote=True)


def _table(t: Table) -> str:
    out = []
    if t.title:
        out.append(f"<h3>{_e(t.title[:1].upper() + t.title[1:])}</h3>")
    if not t.rows:
        out.append('<p class="note">(none)</p>')
        return "\n".join(out)
    align = (t.align + "l" * len(t.columns))[: len(t.columns)]
    cls = {"r": ' class="r"', "c": ' class="c"', "l": ""}
    head = "".join(f"<th>{_e(c)}</th>" for c in t.columns)
    rows = []
    marked = t.marked or [False] * len(t.rows)
    for r, m in zip(t.rows, marked):
        cells = "".join(f"<td{cls[align[j]]}>{_e(c)}</td>" for j, c in enumerate(r))
        rows.append(f'<tr class="mark">{cells}</tr>' if m else f"<tr>{cells}</tr>")
    out.append(
        f'<div class="scroll"><table class="data"><thead><tr>{head}</tr></thead>'
        f"<tbody>{''.join(rows)}</tbody></table></div>"
    )
    if t.note:
        out.append(f'<p class="note">{_e(t.note)}</p>')
    return "\n".join(out)


def _section(sec: Section, number: int, images: dict[str, bytes], fig_note: str) -> str:
    out = [
        f'<section id="{_e(sec.key)}">',
        f'<h2><span class="no">{number}</span>{_e(sec.title)}</h2>',
    ]
    if sec.key == "warnings":
        msgs = sec.values.get("messages", [])
        if msgs:
            out.append('<ul class="warn">' + "".join(f"<li>{_e(m)}</li>" for m in msgs) + "</ul>")
        else:
            out.append('<p class="none">No warnings.</p>')
    elif sec.items:
        rows = "".join(f"<tr><th>{_e(k)}</th><td>{_e(v)}</td></tr>" for k, v in sec.items)
        out.append(f'<table class="kv">{rows}</table>')
    for t in sec.tables:
        out.append(_table(t))
    for p in sec.text:
        out.append(f'<p class="text">{_e(p)}</p>')
    captions = sec.values.get("captions", {})  # a section's own (e.g. a block not flown)
    for name in sec.figures:
        if name in images:
            b64 = base64.b64encode(images[name]).decode("ascii")
            out.append(
                f'<figure><img alt="{_e(name)}" src="data:image/png;base64,{b64}">'
                f"<figcaption>{_e(captions.get(name) or CAPTIONS.get(name, ''))}</figcaption>"
                "</figure>"
            )
        elif fig_note:
            out.append(f'<p class="note">[figure {_e(name)} omitted: {_e(fig_note)}]</p>')
    out.append("</section>")
    return "\n".join(out)


def _cards(report: Report) -> str:
    cards = []
    s0 = report.section("sigma0")
    if s0 is not None:
        t = s0.values["test"]
        state = "" if t["accepted"] is None else ("ok" if t["accepted"] else "bad")
        note = {None: "no test (r = 0)", True: "χ² test accepted", False: "χ² test rejected"}
        cards.append((state, "σ0 a posteriori", f"{s0.values['sigma0']:.3f}", note[t["accepted"]]))
    red = report.section("redundancy")
    if red is not None:
        cards.append(
            ("", "redundancy r", str(red.values["r"]), f"r/n = {red.values['mean_r']:.3f}")
        )
    chk = report.section("check")
    if chk is not None:
        rms, f = chk.values["rms_m"], 1000.0 if chk.values["unit"] == "mm" else 1.0
        cards.append(
            (
                "",
                "check-point μXY / μZ",
                f"{np.hypot(rms[0], rms[1]) / np.sqrt(2) * f:.1f} / {rms[2] * f:.1f}",
                f"{chk.values['unit']}, {len(chk.values['ids'])} points",
            )
        )
    res = report.section("residuals")
    if res is not None:
        n = res.values["n_flagged"]
        cards.append(
            (
                "bad" if n else "ok",
                "|w| > critical",
                str(n),
                f"critical value {res.values['critical']:g}",
            )
        )
    n = len(report.warnings)
    cards.append(("bad" if n else "ok", "warnings", str(n), "see the last section"))
    return (
        '<div class="cards">'
        + "".join(
            f'<div class="card {c}"><div class="k">{_e(k)}</div><div class="v">{_e(v)}</div>'
            f'<div class="n">{_e(n_)}</div></div>'
            for c, k, v, n_ in cards
        )
        + "</div>"
    )


def html_report(report: Report, *, figures: bool = True, version: str = "", dpi: int = 90) -> str:
    """The report as a self-contained HTML document.

    Parameters
    ----------
    report : Report
        From :func:`~orientviz.report.build_report`.
    figures : bool
        Embed the figures (needs matplotlib; without it the report says they are omitted).
    version : str
        Program version for the footer.
    dpi : int
        Resolution of the embedded PNGs.

    Returns
    -------
    str
        The HTML text (UTF-8).
    """
    images: dict[str, bytes] = {}
    fig_note = ""
    names = [n for s in report.sections for n in s.figures]
    if figures and names:
        try:
            from ..plot.report_figures import report_figures  # matplotlib: optional, GUI-free core
        except ImportError:
            fig_note = "matplotlib is not installed (pip install 'orientviz[plot]')"
        else:
            with np.errstate(all="ignore"):
                images = report_figures(report.plot, names, dpi=dpi)
    elif names:
        fig_note = "figures were not requested"
    nav = " ".join(
        f'<a href="#{_e(s.key)}">{k}. {_e(s.title)}</a>' for k, s in enumerate(report.sections, 1)
    )
    body = "\n".join(_section(s, k, images, fig_note) for k, s in enumerate(report.sections, 1))
    foot = f"orientviz {version}" if version else "orientviz"
    note = f'<p class="note">Figures omitted: {_e(fig_note)}.</p>' if fig_note and names else ""
    return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{_e(report.title)}</title>
<style>{CSS}</style>
</head>
<body>
<div class="page">
<header><h1>{_e(report.title)}</h1><div class="sub">{_e(report.subtitle)}</div></header>
{_cards(report)}
{note}
<nav>{nav}</nav>
{body}
<footer>{_e(foot)} · all standard deviations a posteriori unless stated · residuals v = f(x̂) − l</footer>
</div>
</body>
</html>
"""


def report_format(path: str | os.PathLike[str]) -> str:
    """``"html"`` or ``"text"`` from the suffix of ``path`` (InputError for others)."""
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise InputError(
            f"report format not recognised from the suffix {suffix or '(none)'!r}: use .html or .txt",
            str(path),
        )
    return FORMATS[suffix]


def write_report(
    problem: Problem,
    solution: Solution,
    path: str | os.PathLike[str],
    *,
    figures: bool = True,
    largest: int = 10,
    correlation: float = 0.9,
    alpha: float = 0.05,
) -> Path:
    """Write the adjustment report of a solved problem; HTML or text by the suffix.

    Parameters
    ----------
    problem : Problem
        The loaded problem (:func:`orientviz.io.problem.load_problem`).
    solution : Solution
        Its solution (:func:`orientviz.io.solve.solve_problem`).
    path : str or path-like
        ``*.html`` (self-contained, with figures) or ``*.txt`` (fixed-width text).
    figures : bool
        Embed figures in HTML (ignored for text).
    largest : int
        Number of largest normalised residuals listed.
    correlation : float
        ``|ρ|`` above which pairs of parameters are listed.
    alpha : float
        Significance level of the χ² test of σ̂0 (two-sided).

    Returns
    -------
    pathlib.Path
        The file written (atomically: complete or not at all).

    Raises
    ------
    InputError
        Unknown suffix, or the file cannot be written.

    Examples
    --------
    >>> from orientviz.io.problem import load_problem            # doctest: +SKIP
    >>> from orientviz.io.solve import solve_problem             # doctest: +SKIP
    >>> problem = load_problem("block.json")                     # doctest: +SKIP
    >>> write_report(problem, solve_problem(problem), "at.html")  # doctest: +SKIP
    """
    kind = report_format(path)
    report = build_report(problem, solution, largest=largest, correlation=correlation, alpha=alpha)
    if kind == "html":
        text = html_report(report, figures=figures, version=__version__)
    else:
        text = text_report(report, version=__version__)
    try:
        write_atomic(path, text)
    except OSError as exc:
        raise InputError(f"cannot write the report: {exc.strerror or exc}", str(path)) from None
    return Path(path)
