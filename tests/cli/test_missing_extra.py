"""A command that needs an optional package names the extra to install (exit 2).

The missing package is simulated in a child process by ``sys.modules[name] = None``,
which makes every ``import name`` (and ``import name.sub``) raise ModuleNotFoundError as
on a machine without it.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from orientviz.cli import OPTIONAL_PACKAGES, missing_package_message

_RUN = (
    "import sys\n"
    "for m in sys.argv[1].split(','): sys.modules[m] = None\n"
    "from orientviz.cli import main\n"
    "sys.exit(main(sys.argv[2:]))\n"
)


def _run(blocked: str, *argv: str, cwd) -> subprocess.CompletedProcess:
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run(
        [sys.executable, "-c", _RUN, blocked, *argv],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=env,
        timeout=300,
    )


@pytest.mark.parametrize(
    ("blocked", "argv", "extra"),
    [
        ("matplotlib", ("solve", "resection_example", "--report", "r.html"), "plot"),
        ("viser", ("view", "radar", "--export", "radar.html"), "viewer"),
    ],
)
def test_a_missing_optional_package_names_its_extra(tmp_path, blocked, argv, extra):
    r = _run(blocked, *argv, cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    line = r.stderr.strip()
    assert "\n" not in line and "internal error" not in line
    assert f"'{blocked}'" in line
    assert f'pip install "orientviz[{extra}]"' in line
    assert f'pip install -e ".[{extra}]"' in line
    assert not (tmp_path / argv[-1]).exists()


#: The commands of the core, run one after another in one child process in which every
#: optional package is blocked (an import of one fails whichever command comes first); the
#: exit codes come back on the last line.
_RUN_ALL = (
    "import json, sys\n"
    "for m in sys.argv[1].split(','): sys.modules[m] = None\n"
    "from orientviz.cli import main\n"
    "codes = [main(argv) for argv in json.loads(sys.argv[2])]\n"
    "print('exit codes:', json.dumps(codes))\n"
)


def test_core_commands_need_no_optional_package(tmp_path):
    blocked = ",".join(OPTIONAL_PACKAGES)
    commands = [
        ["solve", "block_strip"],
        ["solve", "block_strip", "--report", "r.txt"],
        ["export", "block_strip", "-d", "out"],
        ["reproduce", "geier"],
    ]
    r = subprocess.run(
        [sys.executable, "-c", _RUN_ALL, blocked, json.dumps(commands)],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=dict(os.environ, MPLBACKEND="Agg"),
        timeout=600,
    )
    assert r.returncode == 0, r.stderr
    last = r.stdout.strip().splitlines()[-1]
    assert last.startswith("exit codes: "), (last, r.stderr)
    codes = json.loads(last.removeprefix("exit codes: "))
    assert codes == [0] * len(commands), (list(zip(commands, codes)), r.stderr)
    assert (tmp_path / "r.txt").stat().st_size > 0
    assert (tmp_path / "out" / "points.csv").is_file()


def test_every_optional_package_is_in_its_extra():
    tomllib = pytest.importorskip("tomllib")
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    extras = tomllib.loads((root / "pyproject.toml").read_text(encoding="utf-8"))["project"][
        "optional-dependencies"
    ]
    dist = {"cv2": "opencv-python-headless", "myst_nb": "myst-nb"}
    for module, extra in OPTIONAL_PACKAGES.items():
        name = dist.get(module, module)
        assert any(d.split(">")[0].split("[")[0] == name for d in extras[extra]), (module, extra)


def test_orientviz_own_missing_module_is_not_called_an_install_problem():
    exc = ModuleNotFoundError("No module named 'orientviz.nothing'", name="orientviz.nothing")
    assert missing_package_message("solve", exc) is None
    core = ModuleNotFoundError("No module named 'numpy'", name="numpy")
    assert "reinstall" in missing_package_message("solve", core)
