"""Every numbered example (examples/NN_*.py) runs, says something true, and uses only the face.

Each example runs in its own Python process (as a user would run it); the checks read
its printed numbers. σ̂0 bands are the two-sided 99.9 % interval of σ̂0 = √(χ²_r / r)
for the example's redundancy r (the simulated noise is what the a-priori σ says);
error/σ bounds are Student's t at 99.9 % with the same r.
"""

from __future__ import annotations

import ast
import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import pytest
from scipy import stats

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted((ROOT / "examples").glob("[0-9][0-9]_*.py"))
ALLOWED_IMPORTS = {"numpy", "orientviz", "sys", "tempfile", "pathlib"}


def _number(pattern: str, text: str) -> float:
    m = re.search(pattern, text)
    assert m, f"the example did not print {pattern!r}:\n{text}"
    return float(m.group(1))


def _sigma0(out: str) -> tuple[float, int]:
    """σ̂0 and redundancy of the last result the example printed (its final one)."""
    found = re.findall(
        r"sigma0 = ([0-9.]+)(?:  |\s*\(a-posteriori, unit weight\), )redundancy =? ?(\d+)", out
    )
    assert found, f"no 'sigma0 = …, redundancy …' line in:\n{out}"
    return float(found[-1][0]), int(found[-1][1])


def _sigma0_in_band(out: str) -> int:
    s0, r = _sigma0(out)
    lo, hi = (float(v) for v in (stats.chi2.ppf(0.0005, r) / r, stats.chi2.ppf(0.9995, r) / r))
    assert lo**0.5 <= s0 <= hi**0.5, f"σ̂0 = {s0} outside [{lo**0.5:.3f}, {hi**0.5:.3f}] for r = {r}"
    return r


def _t_bound(r: int) -> float:
    return float(stats.t.ppf(0.9995, r))


def check_01(out: str) -> None:
    r = _sigma0_in_band(out)
    assert _number(r"largest error / σ: ([0-9.]+)", out) < _t_bound(r)
    assert "converged" in out and "NOT converged" not in out


def check_02(out: str) -> None:
    r = _sigma0_in_band(out)
    assert _number(r"largest angle error / σ: ([0-9.]+)", out) < _t_bound(r)
    assert _number(r"model points: (\d+)", out) == 15


def check_03(out: str) -> None:
    _sigma0_in_band(out)
    ratios = re.search(r"true / predicted: ([0-9.]+) ([0-9.]+) ([0-9.]+)", out)
    assert ratios, out
    # errors of neighbouring points are correlated (the block deforms as a whole), so the
    # RMS over the tie points is not a χ² sample; a factor 2 either way would mean a
    # wrong cofactor or a forgotten σ̂0
    assert all(0.5 < float(v) < 2.0 for v in ratios.groups()), ratios.group(0)


def check_04(out: str) -> None:
    _sigma0_in_band(out)
    # COLMAP's pose → orientviz's centre: only the 1 µm rounding of the written t remains
    assert _number(r"written centres: largest ([0-9.]+) mm", out) < 0.01
    assert _number(r"reprojection RMS before the adjustment: ([0-9.]+) px", out) > 0.5


def check_05(out: str) -> None:
    _sigma0_in_band(out)
    assert re.search(r"viewer running at http://127\.0\.0\.1:\d+", out), out
    assert "an HTML page: True" in out
    assert _number(r"static snapshot: block\.html, ([0-9.]+) MB", out) > 0.05
    assert "viewer stopped" in out


def check_06(out: str) -> None:
    _sigma0_in_band(out)
    # the distortion bends the heights of the plain bundle; self-calibration must remove
    # most of it (the ratio is 1 if the parameters absorb nothing)
    assert _number(r"self-calibration / plain = ([0-9.]+)", out) < 0.6
    assert "kept: none" not in out


def check_07(out: str) -> None:
    m = re.search(r"corrupted rays found: (\d+) of (\d+)", out)
    assert m and m.group(1) == m.group(2), out
    assert _number(r"good rays eliminated too: (\d+)", out) <= 10


CHECKS = {
    "01_resection.py": check_01,
    "02_relative_orientation.py": check_02,
    "03_bundle_block.py": check_03,
    "04_colmap_import.py": check_04,
    "05_view_result.py": check_05,
    "06_self_calibration.py": check_06,
    "07_gross_errors.py": check_07,
}
NEEDS = {"05_view_result.py": "viser"}


def test_every_example_has_a_check():
    assert len(EXAMPLES) >= 5
    assert sorted(p.name for p in EXAMPLES) == sorted(CHECKS)


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_example_shape(path):
    # a title docstring, a main(), and only the face (import orientviz as ov), numpy and
    # the standard library: a user can copy it as it is
    tree = ast.parse(path.read_text(encoding="utf-8"))
    doc = ast.get_docstring(tree)
    assert doc and re.match(r"\d\d — \S", doc), "first line: 'NN — Title'"
    assert any(isinstance(n, ast.FunctionDef) and n.name == "main" for n in tree.body)
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                assert a.name.split(".")[0] in ALLOWED_IMPORTS, a.name
                if a.name == "orientviz":
                    assert a.asname == "ov", "import orientviz as ov"
                assert a.name == "orientviz" or not a.name.startswith("orientviz"), a.name
        elif isinstance(node, ast.ImportFrom):
            assert node.module and node.module.split(".")[0] in ALLOWED_IMPORTS - {"orientviz"}, (
                f"from {node.module} import …: use ov.<name>"
            )


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_example_runs(path, tmp_path):
    need = NEEDS.get(path.name)
    if need and importlib.util.find_spec(need) is None:
        pytest.skip(f"{need} is not installed (pip install orientviz[viewer])")
    proc = subprocess.run(
        [sys.executable, str(path)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    CHECKS[path.name](proc.stdout)
