"""Read the numbers of a DBAT result file (``report.txt``) as printed.

DBAT (N. Börlin's Damped Bundle Adjustment Toolbox) writes its bundle results as an
indented text file: one item per line, three spaces per level, ``Key: value`` leaves,
headings with their items below them, and comma-separated tables (a header line
``id, x, y, …`` followed by rows). :func:`parse_report` turns it into a tree;
:func:`report_values` picks the published numbers that orientviz reproduces, keeping
each value as the printed string (its digits are the reproduction's tolerance).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import Row

INDENT = 3


@dataclass
class Node:
    """One line of the report and the more deeply indented lines below it."""

    text: str
    children: list[Node] = field(default_factory=list)

    @property
    def key(self) -> str:
        return self.text.split(":", 1)[0].strip()

    @property
    def value(self) -> str:
        """The text after the first ``:`` (stripped), ``""`` if none."""
        return self.text.split(":", 1)[1].strip() if ":" in self.text else ""

    def child(self, prefix: str) -> Node:
        """The first child whose text starts with ``prefix`` (KeyError if none)."""
        for c in self.children:
            if c.text.startswith(prefix):
                return c
        raise KeyError(f"DBAT report: no {prefix!r} under {self.text!r}")

    def find(self, *path: str) -> Node:
        node = self
        for p in path:
            node = node.child(p)
        return node

    def field(self, name: str) -> str:
        """The printed number of leaf ``name`` (its unit dropped): ``"0.829772"``."""
        return self.child(name + ":").value.split()[0] if self.child(name + ":").value else ""

    def table(self) -> list[dict[str, str]]:
        """The comma-separated table below this node: header line, then rows."""
        header = [h.strip() for h in self.children[0].text.split(",")]
        rows = []
        for c in self.children[1:]:
            cells = [v.strip() for v in c.text.split(",")]
            if len(cells) == len(header):
                rows.append(dict(zip(header, cells)))
        return rows


def parse_report(text: str) -> Node:
    """The report as a tree of :class:`Node` (the root's text is the title line)."""
    lines = [ln.rstrip() for ln in text.splitlines() if ln.strip()]
    root = Node(lines[0].strip())
    stack: list[tuple[int, Node]] = [(-1, root)]
    for ln in lines[1:]:
        depth = (len(ln) - len(ln.lstrip(" "))) // INDENT
        node = Node(ln.strip())
        while stack[-1][0] >= depth:
            stack.pop()
        stack[-1][1].children.append(node)
        stack.append((depth, node))
    return root


def read_report(path: str | Path) -> Node:
    """Parse the DBAT report at ``path``."""
    return parse_report(Path(path).read_text(encoding="utf-8"))


#: (report heading, orientviz quantity) of the exterior orientation, DBAT's order.
EO_FIELDS = (
    ("Omega", "omega [deg]"),
    ("Phi", "phi [deg]"),
    ("Kappa", "kappa [deg]"),
    ("Xc", "X0 [m]"),
    ("Yc", "Y0 [m]"),
    ("Zc", "Z0 [m]"),
)
EO_ORDER = [head for head, _ in EO_FIELDS]
#: DBAT's order ω φ κ Xc Yc Zc → positions in orientviz's X0 Y0 Z0 ω φ κ
_DBAT_ORDER = [3, 4, 5, 0, 1, 2]
EO_NAMES = {head: name.split()[0] for head, name in EO_FIELDS}


def report_values(root: Node) -> dict[str, str]:
    """The published numbers of a DBAT report, keyed ``"<section>|<case>|<quantity>"``.

    Values are the printed strings. Sections: ``summary`` (σ0, σ0 in pixels, redundancy,
    numbers of parameters and observations, last error = √(vᵀPv)), ``residuals``
    (overall point RMS in pixels), ``stations`` (per photo ``"photo k (name)"``: values
    and deviations of ω, φ, κ (deg) and Xc, Yc, Zc (m), and the ω–Yc, φ–Xc correlations
    over 95 %), ``control``/``check`` (posterior X, Y, Z and σ per point),
    ``check differences`` (posterior − prior per check point) and ``check statistics``
    (max and RMS of the 3-D differences), ``camera`` (calibrated interior orientation:
    value and deviation of cc, px, py, as, K1-K3, P1, P2 when present).
    """
    out: dict[str, str] = {}
    info = root.find("Information from last bundle")
    out["summary||sigma0"] = info.field("Sigma0")
    out["summary||sigma0 [px]"] = info.child("Sigma0 (pixels):").value
    out["summary||redundancy"] = info.child("Redundancy").text.split()[-1]
    out["summary||parameters"] = info.field("Number of params")
    out["summary||observations"] = info.field("Number of observations")
    out["summary||sqrt(vTPv)"] = info.find("Total error:").field("Last error")
    cam = info.find("Cameras:")
    if cam.field("Calibration") == "yes":
        camera = cam.children[1]
        short: dict[str, str] = {}
        corr: list[tuple[str, str, str]] = []
        for prefix, name in (
            ("Camera Constant", "c [mm]"), ("px", "px [mm]"), ("py", "py [mm]"),
            ("as", "as"), ("K1", "K1 [mm^-3]"), ("K2", "K2 [mm^-5]"), ("K3", "K3 [mm^-7]"),
            ("P1", "P1 [mm^-3]"), ("P2", "P2 [mm^-3]"),
        ):  # fmt: skip
            node = camera.child(prefix)
            out[f"camera||{name}"] = node.field("Value")
            try:
                out[f"camera||σ {name}"] = node.field("Deviation")
            except KeyError:
                pass
            short[prefix] = name.split()[0]
            for c in node.children:
                if c.text.startswith("Correlations over 95%:"):
                    for item in c.value.rstrip(".").split(","):
                        other, pct = item.strip().split(":")
                        corr.append((short[prefix], other, pct.rstrip("%")))
        order = list(short.values())
        for a, b, pct in corr:
            if b in order:
                a, b = sorted((a, b), key=order.index)
                out.setdefault(f"camera||correlation {a}-{b} [%]", pct)
    photos = info.find("Precisions / Standard Deviations:", "Photograph Standard Deviations:")
    for k, photo in enumerate(photos.children, start=1):
        case = f"photo {k} ({photo.value})"
        for head, name in EO_FIELDS:
            node = photo.child(head + ":")
            out[f"stations|{case}|{name}"] = node.field("Value")
            try:  # a parameter held for the datum has no deviation
                out[f"stations|{case}|σ {name}"] = node.field("Deviation")
            except KeyError:
                pass
            for c in node.children:
                if c.text.startswith("Correlations over 95%:"):
                    for item in c.value.rstrip(".").split(","):
                        other, pct = item.strip().split(":")
                        a, b = sorted((head, other), key=EO_ORDER.index)
                        pair = f"correlation {EO_NAMES[a]}-{EO_NAMES[b]} [%]"
                        out.setdefault(f"stations|{case}|{pair}", pct.rstrip("%"))
    quality = root.find("Quality")
    marks = quality.find("Point Marking Residuals")
    out["residuals||overall point RMS [px]"] = marks.field("Overall point RMS")
    for section, heading in (("control", "Ctrl measurements"), ("check", "Check measurements")):
        try:
            node = quality.child(heading)
            posterior = node.child("Posterior")
        except KeyError:
            continue
        for row in posterior.table():
            case = f"point {row['id']} ({row['label']})"
            for a in "xyz":
                out[f"{section}|{case}|{a.upper()} [m]"] = row[a]
                out[f"{section}|{case}|σ {a.upper()} [m]"] = row[f"std{a}"]
        if section == "check":
            for row in node.child("Diff").table():
                case = f"point {row['id']} ({row['label']})"
                for a in ("x", "y", "z", "xy", "xyz"):
                    out[f"check differences|{case}|d{a.upper()} [m]"] = row[a]
            delta = node.child("Check point delta")
            out["check statistics||max 3-D difference [m]"] = delta.field("Max")
            out["check statistics||RMS 3-D difference [m]"] = delta.field("RMS")
    return out


_EXP = re.compile(r"^([+-]?)(\d+)(?:\.(\d+))?e([+-]?\d+)$")


def as_printed(values: dict[str, str]) -> tuple[dict[str, str | float], dict[str, int]]:
    """The report's values for the reproduction rows, and the decimals DBAT printed.

    Plain decimals stay strings (their digits are the tolerance); numbers DBAT printed in
    exponent notation (``%g``: ``-4.51351e-05``) become floats with the number of decimals
    they were printed to (``-4.51351e-05`` → 10), so that the rows' flags can read them.
    """
    out: dict[str, str | float] = {}
    decimals: dict[str, int] = {}
    for key, text in values.items():
        m = _EXP.match(text)
        if m:
            out[key] = float(text)
            decimals[key] = max(len(m.group(3) or "") - int(m.group(4)), 0)
        else:
            out[key] = text
    return out, decimals


def station_numbers(out: dict[str, float], case: str, values, sigma, Q) -> None:
    """Put one station's numbers under the report's keys into ``out``.

    ``values``, ``sigma``: (6,) in DBAT's order ω, φ, κ (deg), Xc, Yc, Zc (m); ``Q``: the
    station's 6 × 6 cofactor block in orientviz's order X0 Y0 Z0 ω φ κ (the correlations
    DBAT lists over 95 % are computed for every pair).
    """
    q = np.asarray(Q)[np.ix_(_DBAT_ORDER, _DBAT_ORDER)]
    rho = q / np.sqrt(np.outer(np.diag(q), np.diag(q)))
    for j, (_, name) in enumerate(EO_FIELDS):
        out[f"stations|{case}|{name}"] = float(values[j])
        out[f"stations|{case}|σ {name}"] = float(sigma[j])
        for jj in range(j + 1, 6):
            other = EO_FIELDS[jj][1].split()[0]
            out[f"stations|{case}|correlation {name.split()[0]}-{other} [%]"] = 100.0 * rho[j, jj]


def predicted_rows(
    paper: dict[str, Any],
    mine: dict[str, float],
    decimals: dict[str, int],
    shown: Callable[[str, float], str] = lambda key, value: f"{value:.7g}",
    note: Callable[[str, float | None], str] = lambda key, value: (
        "" if value is not None else "not computed by orientviz"
    ),
) -> list:
    """One predicted :class:`~orientviz.reproduce.Row` per published number: DBAT's as
    printed beside orientviz's (``shown`` formats it, ``note`` explains it)."""
    rows = []
    for key, printed in paper.items():
        section, case, quantity = key.split("|")
        value = mine.get(key)
        rows.append(
            Row(
                section,
                case,
                quantity,
                printed,
                None if value is None else shown(key, value),
                note=note(key, value),
                label="predicted",
                value=value,
                decimals=decimals.get(key) if isinstance(printed, float) else None,
                key=key,
                group=section,
            )
        )
    return rows
