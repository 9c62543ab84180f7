"""The package as others receive it: built by ``python -m build``, installed from the wheel.

The build runs with build isolation (setuptools comes from the package index, as on any
machine that builds the project); the wheel goes into a fresh virtual environment that
sees this machine's numpy/scipy/jsonschema (``--system-site-packages``) but not the
source tree, so the solve below can only succeed if the wheel carries the code, the
schemas and the shipped examples.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tarfile
import venv
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.slow
tomllib = pytest.importorskip("tomllib")  # Python ≥ 3.11


def _clean_env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # else setuptools warns it cannot byte-compile
    env["PIP_DISABLE_PIP_VERSION_CHECK"] = "1"
    return env


def test_pyproject_metadata_is_what_the_ecosystem_expects():
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert meta["license"] == "BSD-3-Clause"  # an SPDX expression, not a table
    assert not any(c.startswith("License ::") for c in meta["classifiers"])
    versions = [
        c for c in meta["classifiers"] if c.startswith("Programming Language :: Python :: 3.")
    ]
    assert len(versions) >= 3
    for url in meta.get("urls", {}).values():
        assert "example" not in url and "invalid" not in url
    extras = meta["optional-dependencies"]
    assert any(d.startswith("pycolmap") for d in extras["bench"])
    flat = " ".join(d for deps in extras.values() for d in deps)
    assert "nbmake" not in flat  # no test or tool uses it


def test_build_gives_wheel_and_sdist_without_warnings_and_the_wheel_solves(tmp_path):
    dist = tmp_path / "dist"
    # a tree people build from has run Python: its data folders hold __pycache__
    subprocess.run(
        [sys.executable, "-c", "import orientviz.datasets"],
        check=True,
        env={**_clean_env(), "PYTHONPATH": str(ROOT / "src")},
        timeout=120,
    )
    assert (ROOT / "src" / "orientviz" / "datasets" / "__pycache__").is_dir()
    build = subprocess.run(
        [sys.executable, "-m", "build", "--outdir", str(dist), str(ROOT)],
        capture_output=True,
        text=True,
        env=_clean_env(),
        timeout=600,
    )
    log = build.stdout + build.stderr
    assert build.returncode == 0, log[-3000:]
    warnings = [line for line in log.splitlines() if "warning" in line.lower()]
    assert warnings == [], "\n".join(warnings)
    wheels = sorted(dist.glob("orientviz-*.whl"))
    sdists = sorted(dist.glob("orientviz-*.tar.gz"))
    assert len(wheels) == 1 and len(sdists) == 1
    with zipfile.ZipFile(wheels[0]) as whl, tarfile.open(sdists[0]) as sdist:
        names = whl.namelist() + sdist.getnames()
    assert not [n for n in names if "__pycache__" in n or n.endswith(".pyc")], "bytecode shipped"

    env_dir = tmp_path / "venv"
    # no pip of its own (ensurepip: ~3 s CPU): the pip it sees among the system's packages
    # installs into the environment it runs in, this one
    venv.EnvBuilder(system_site_packages=True, with_pip=False).create(env_dir)
    py = env_dir / "bin" / "python"
    subprocess.run(
        [str(py), "-m", "pip", "install", "-q", "--no-deps", "--no-index", str(wheels[0])],
        check=True,
        env=_clean_env(),
        timeout=300,
        cwd=tmp_path,
    )
    where = subprocess.run(
        [str(py), "-c", "import orientviz; print(orientviz.__file__)"],
        capture_output=True,
        text=True,
        env=_clean_env(),
        cwd=tmp_path,
        check=True,
    ).stdout.strip()
    assert Path(where).is_relative_to(env_dir), where  # the wheel's copy, not the source tree
    solve = subprocess.run(
        [str(env_dir / "bin" / "orientviz"), "solve", "resection_example", "--json"],
        capture_output=True,
        text=True,
        env=_clean_env(),
        cwd=tmp_path,
        timeout=120,
    )
    assert solve.returncode == 0, solve.stderr
    result = json.loads(solve.stdout)
    assert result["converged"] is True
    assert result["redundancy"] > 0
