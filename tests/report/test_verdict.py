"""One verdict everywhere: terminal, --json, text and HTML report agree.

For shipped examples whose global test is accepted (resection_example), rejected with
σ0 too small (block_strip) and rejected with flagged observations (dbat_sxb), the
global test, the number of flagged observations and the warnings are read from each of
the four outputs of ``orientviz solve`` and compared.
"""

from __future__ import annotations

import html
import json
import re

import pytest

from orientviz.cli import main


def _solve(capsys, *argv: str) -> tuple[str, str]:
    rc = main(["solve", *argv])
    out = capsys.readouterr()
    assert rc == 0, out.err
    return out.out, out.err


@pytest.mark.parametrize(
    ("name", "expect"),
    [("resection_example", "accepted"), ("block_strip", "rejected"), ("dbat_sxb", "rejected")],
)
def test_terminal_json_text_and_html_report_give_one_verdict(tmp_path, capsys, name, expect):
    txt, page = tmp_path / "r.txt", tmp_path / "r.html"
    terminal, err = _solve(capsys, name, "--report", str(txt))
    assert f"wrote {txt}" in err and "text report" in err
    data = json.loads(_solve(capsys, name, "--json")[0])
    test, warnings = data["global_test"], data["warnings"]
    assert test["result"] == expect
    assert (test["sigma0_lower"] <= data["sigma0"] <= test["sigma0_upper"]) == (
        expect == "accepted"
    )

    # terminal: the same test, the same flags and the same warnings
    assert f": {expect.upper()}: σ0 = {data['sigma0']:.3f}" in terminal
    n_flagged = len(data["flagged"])
    flag_line = re.search(r"flagged \(\|w\| > [\d.]+\): (none|(\d+) observation)", terminal)
    assert (0 if flag_line.group(1) == "none" else int(flag_line.group(2))) == n_flagged
    if warnings:
        assert f"warnings: {len(warnings)}\n" in terminal
        for k, message in enumerate(warnings, 1):
            assert f"  ! {k}. {message}" in terminal
    else:
        assert "warnings: none" in terminal
    assert (expect == "rejected") == any(w.startswith("global test rejected") for w in warnings)

    # text report: header, section 2's result, section 7's count, section 9's list
    report = txt.read_text(encoding="utf-8")
    assert f"warnings: {len(warnings)}" in report.splitlines()[5]
    result_line = next(line for line in report.splitlines() if line.strip().startswith("result"))
    assert ("REJECTED" in result_line) == (expect == "rejected")
    assert ("accepted" in result_line) == (expect == "accepted")
    above = next(line for line in report.splitlines() if "observations above it" in line)
    assert int(above.split()[-1]) == n_flagged
    flat = " ".join(report.split())
    for message in warnings:
        assert " ".join(message.split()) in flat

    # HTML report: the cards and the warnings section
    _solve(capsys, name, "--report", str(page))
    doc = html.unescape(page.read_text(encoding="utf-8"))
    assert f"χ² test {expect}" in doc
    assert re.search(r'warnings</div><div class="v">(\d+)<', doc).group(1) == str(len(warnings))
    assert re.search(r'\|w\| > critical</div><div class="v">(\d+)<', doc).group(1) == str(n_flagged)
    for message in warnings:
        assert message in doc


def test_counts_are_named_by_what_they_count(capsys):
    terminal, _ = _solve(capsys, "block_strip")
    head = terminal.splitlines()[0]
    n = int(re.search(r"(\d+) observations, ", head).group(1))
    block = next(line for line in terminal.splitlines() if line.startswith("block: "))
    rays = int(re.search(r"(\d+) image points \(each 2 image coordinates\)", block).group(1))
    not_adjusted = int(re.search(r"reported but not adjusted: (\d+) observations", head).group(1))
    assert n + not_adjusted == 2 * rays  # observations are image coordinates
    assert "observations (" not in block


def test_view_export_says_what_it_wrote_and_shows_no_server_box(tmp_path, capfd):
    pytest.importorskip("viser")
    out = tmp_path / "radar.html"
    assert main(["view", "radar", "--export", str(out)]) == 0
    printed = capfd.readouterr()
    assert printed.out.strip() == f"orientviz view: wrote {out}"
    assert "viser" not in printed.err and "http" not in printed.err.lower()
    assert out.stat().st_size > 10_000


@pytest.mark.parametrize("name", ["kovarik", "geier"])
def test_reproduce_fits_100_columns_and_translates_the_german(name):
    from orientviz import reproduce

    rows = reproduce.run(name)
    narrow = reproduce.format_rows(rows, 100)  # what `orientviz reproduce NAME` prints
    assert max(len(line) for line in narrow.splitlines()) <= 100
    wide = reproduce.format_rows(rows)  # `--wide`: one line per row
    assert max(len(line) for line in wide.splitlines()) > 100
    german = {
        "kovarik": [("'um eine Zehner-Potenz kleiner'", "(smaller by a power of ten)"),
                    ("'rund dreimal'", "(about three times)")],
        "geier": [("Willk. Höhen Fig. 7", "(arbitrary heights"), ("Ebene", "(plane)"),
                  ('"Keine brauchbare Lösung"', "no usable solution")],
    }[name]  # fmt: skip
    flat = " ".join(narrow.split())
    for quote, english in german:
        assert f"{quote} {english}" in flat or f"{quote}: {english}" in flat, quote


def test_reproduce_command_wraps_unless_wide(capsys):
    assert main(["reproduce", "kovarik"]) == 0
    assert max(len(line) for line in capsys.readouterr().out.splitlines()) <= 100
    assert main(["reproduce", "kovarik", "--wide"]) == 0
    assert max(len(line) for line in capsys.readouterr().out.splitlines()) > 100
