"""Every command in the README is run: here, by another test (named), or by .ci/run.

The README opens with two commands: the main job (install the viewer's extra, open the
viewer) and the test command, which must be the line .ci/run calls. The main-job line
is run for real in a fresh virtual environment (slow test): it must install all that
`orientviz view` and an HTML report need.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
import time
import venv
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
README = (ROOT / "README.md").read_text(encoding="utf-8")
CI_RUN = (ROOT / ".ci" / "run").read_text(encoding="utf-8")

MAIN_JOB = 'pip install -e ".[viewer]" && orientviz view'
TEST_COMMAND = 'pip install -e ".[all]" && python -m pytest'
REPORT_COMMAND = "orientviz solve block_strip --report report.html"

#: command → (test file that runs it, text that file must contain)
BY_TESTS = {
    "jupyter lab notebooks/": ("tests/integration/test_jupyterlab.py", '"-m", "jupyterlab"'),
    "python -m sphinx -b html book book/_build/html": (
        "tests/book/test_book.py",
        '"-m", "sphinx", "-b", "html"',
    ),
    "orientviz view pair": ("tests/viewer/test_browser_demos.py", 'load_demo("pair")'),
    'pip install -e ".[notebooks]"': (
        "tests/integration/test_readme.py",
        "test_the_notebooks_and_book_extras_hold_what_they_need",
    ),
    'pip install -e ".[book]"': (
        "tests/integration/test_readme.py",
        "test_the_notebooks_and_book_extras_hold_what_they_need",
    ),
    "python3 -m venv .venv && . .venv/bin/activate": (
        "tests/integration/test_readme.py",
        "test_the_main_job_line_in_a_fresh_venv",
    ),
    "orientviz view axe.json --free": (
        "tests/viewer/test_browser_sfm.py",
        'ViewerApp(demo_from_file(str(path), {"free": True})',
    ),
    MAIN_JOB: ("tests/integration/test_readme.py", "test_the_main_job_line_in_a_fresh_venv"),
    # run in the fresh venv after the main job's install (its output checked there as here)
    REPORT_COMMAND: ("tests/integration/test_readme.py", "test_the_main_job_line_in_a_fresh_venv"),
}
#: commands run here (no server, quick)
HERE = (
    "orientviz solve block_strip --json",
    "orientviz reproduce",
)
#: the README's lines on one's own reconstruction, run in order in one folder
SFM = (
    "orientviz import-colmap axe -o axe.json",
    "orientviz solve axe.json --free -o solved.json",
    "orientviz import-bal ladybug -o lb.json",
    "orientviz solve lb.json --free -o lb_solved.json && orientviz export-bal lb_solved.json -o lb_solved.bal",
)
#: commands CI runs: verbatim, or as the same pytest run with other output options
BY_CI = (
    TEST_COMMAND,
    "apt-get install -y chromium chromium-driver",
    "python -m pytest -v",
    "python -m pytest tests/report -q",
)


def readme_commands() -> list[str]:
    """Every line of the README's bash blocks, without its comment."""
    out = []
    for block in re.findall(r"```bash\n(.*?)```", README, re.S):
        for line in block.splitlines():
            cmd = re.split(r"\s#\s", line)[0].strip()
            if cmd:
                out.append(cmd)
    return out


def test_the_readme_opens_with_the_main_job_and_the_ci_test_command():
    first = readme_commands()[:2]
    assert first == [MAIN_JOB, TEST_COMMAND]
    assert README.index(MAIN_JOB) < README.index("## ")  # before the first section
    ci_lines = [line.strip() for line in CI_RUN.splitlines()]
    assert TEST_COMMAND in ci_lines  # verbatim, as its own line


def test_every_readme_command_is_run_somewhere():
    known = set(BY_TESTS) | set(HERE) | set(BY_CI) | set(SFM)
    unknown = [c for c in readme_commands() if c not in known]
    assert not unknown, f"README commands nobody runs: {unknown}"
    for command, (path, marker) in BY_TESTS.items():
        assert marker in (ROOT / path).read_text(encoding="utf-8"), (command, path)
    assert "apt-get install" in CI_RUN and "chromium chromium-driver" in CI_RUN
    assert "python -m pytest" in CI_RUN


@pytest.mark.parametrize("command", HERE)
def test_readme_cli_commands(tmp_path, command):
    env = dict(os.environ, MPLBACKEND="Agg")
    argv = shlex.split(command)
    r = subprocess.run(
        [sys.executable, "-m", "orientviz.cli", *argv[1:]],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=env,
        timeout=600,
    )
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip()
    if "--report" in argv:
        assert (tmp_path / argv[-1]).read_text(encoding="utf-8").startswith("<!DOCTYPE html>")
        assert f"wrote {argv[-1]}" in r.stderr


def test_the_readme_sfm_lines_in_order(tmp_path):
    """Import, solve and export the shipped COLMAP and BAL models as the README shows."""
    env = dict(os.environ, MPLBACKEND="Agg")
    for line in SFM:
        for command in line.split(" && "):
            r = subprocess.run(
                [sys.executable, "-m", "orientviz.cli", *shlex.split(command)[1:]],
                capture_output=True, text=True, cwd=tmp_path, env=env, timeout=600,
            )  # fmt: skip
            assert r.returncode == 0, (command, r.stderr)
    assert (tmp_path / "solved.json").is_file()
    assert (tmp_path / "lb_solved.bal").read_text(encoding="utf-8").startswith("49 7776 31843")


def test_the_notebooks_and_book_extras_hold_what_they_need():
    tomllib = pytest.importorskip("tomllib")
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"][
        "optional-dependencies"
    ]
    names = {k: {re.split(r"[<>=\[ ]", d)[0] for d in v} for k, v in extras.items()}
    # what the lessons import besides the core, and what `jupyter lab` needs
    assert {"matplotlib", "ipywidgets", "jupyterlab", "ipykernel"} <= names["notebooks"]
    # the book executes the lessons and renders them
    assert {"sphinx", "myst-nb", "matplotlib", "ipywidgets", "ipykernel"} <= names["book"]
    assert {"viser", "matplotlib"} <= names["viewer"]
    import json

    imported = set()
    for nb in (ROOT / "notebooks").glob("*.ipynb"):
        for cell in json.loads(nb.read_text(encoding="utf-8"))["cells"]:
            if cell["cell_type"] == "code":
                code = "".join(cell["source"])
                imported |= set(re.findall(r"^\s*(?:import|from) (\w+)", code, re.M))
    # lessons that show the 3D viewer live need viser from both extras
    lessons = [p.read_text(encoding="utf-8") for p in (ROOT / "notebooks").glob("*.ipynb")]
    if any("orientviz.viewer" in text for text in lessons):
        assert "viser" in names["notebooks"] and "viser" in names["book"]
    # besides the standard library: the core and what the notebooks extra brings
    allowed = {"orientviz", "numpy", "scipy", "jsonschema", "matplotlib", "ipywidgets", "IPython"}
    imported -= set(sys.stdlib_module_names)
    assert imported <= allowed, imported - allowed


@pytest.mark.slow
def test_the_main_job_line_in_a_fresh_venv(tmp_path):
    """The README's venv line, then its main-job install, then the viewer and a report.

    A venv of its own (no system packages): pip takes numpy, SciPy, viser, … from its
    cache or the index, as on a new machine. `orientviz view` itself serves until
    Ctrl-C (tests/viewer/test_cli.py runs that); here the same install writes a static
    page and the README's HTML report (:data:`REPORT_COMMAND`, checked as
    :func:`test_readme_cli_commands` checks the README's other commands).
    """
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["PIP_DISABLE_PIP_VERSION_CHECK"] = "1"
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    assert venv  # the README's `python3 -m venv` is this module
    script = (
        f"cd {shlex.quote(str(tmp_path))} && python3 -m venv .venv && . .venv/bin/activate && "
        f"cd {shlex.quote(str(ROOT))} && "
        + MAIN_JOB.replace("&& orientviz view", "")
        # --no-compile: pip's bytecode compilation of SciPy & co. is half the install's
        # CPU (about 11 of 22 s) and tests nothing of ours
        + f" -q --no-compile && cd {shlex.quote(str(tmp_path))}"
        " && orientviz view radar --export radar.html"
        f" && {REPORT_COMMAND} > solve.out 2> solve.err"
        " && python -c 'import orientviz, sys; print(orientviz.__file__, sys.prefix)'"
    )
    t0 = time.monotonic()
    r = subprocess.run(["bash", "-c", script], capture_output=True, text=True, env=env,
                       timeout=1200)  # fmt: skip
    elapsed = time.monotonic() - t0
    assert r.returncode == 0, (r.stdout[-2000:], r.stderr[-3000:])
    where, prefix = r.stdout.strip().splitlines()[-1].split()
    assert Path(prefix) == tmp_path / ".venv" and Path(where).is_relative_to(ROOT / "src")
    assert (tmp_path / "radar.html").stat().st_size > 10_000
    report = (tmp_path / "report.html").read_text(encoding="utf-8")
    assert report.startswith("<!DOCTYPE html>")
    assert "<img" in report  # figures: matplotlib
    assert (tmp_path / "solve.out").read_text(encoding="utf-8").strip()
    assert "wrote report.html" in (tmp_path / "solve.err").read_text(encoding="utf-8")
    print(f"main-job install + view --export + report in a fresh venv: {elapsed:.0f} s")
