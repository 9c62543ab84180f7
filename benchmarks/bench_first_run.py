"""First run: the README's first command on a fresh virtual environment, timed.

Goal (issue 8; issue 29: the first command installs only the viewer's extra): on a fresh
machine, ``pip install -e ".[viewer]" && orientviz view``
installs and opens the default demo in under 3 minutes. Printed, never asserted.

What it does, all inside a temporary directory (nothing else is touched):

1. ``git archive HEAD`` of this checkout → ``<tmp>/orientviz`` (what a fresh clone holds;
   uncommitted work in the tree is left out, and the build writes its egg-info there,
   not into the shared checkout);
2. ``python -m venv <tmp>/venv`` with the interpreter that runs this script;
3. the README's command in that copy, with the venv's pip:
   ``<tmp>/venv/bin/pip install -e ".[viewer]"`` (into that venv only; ``--extra all``
   for the test command's install);
4. ``<tmp>/venv/bin/orientviz view --port P`` (a free port instead of 8080, which may be
   taken on a shared machine): the time until http://127.0.0.1:P/ answers 200, and until
   the command prints its URL (after the default demo's scene is built).

pip's configuration, cache and wheelhouses are used as they are: the report states the
cache size and the configured find-links/indexes, because a warm cache or a local
wheelhouse makes the install much faster than on a fresh machine downloading from PyPI.

Run:  python benchmarks/bench_first_run.py [--keep]
"""

from __future__ import annotations

import argparse
import os
import pathlib
import shutil
import signal
import socket
import subprocess
import sys
import tarfile
import tempfile
import time
import urllib.request

ROOT = pathlib.Path(__file__).resolve().parents[1]
GOAL_S = 180.0


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _run(cmd: list[str], **kw) -> float:
    t = time.perf_counter()
    subprocess.run(cmd, check=True, **kw)
    return time.perf_counter() - t


def _pip_environment() -> str:
    """pip's cache size and configuration, as pip reports them (for the record)."""
    lines = []
    for args in (["cache", "info"], ["config", "list"]):
        out = subprocess.run(
            [sys.executable, "-m", "pip", *args], capture_output=True, text=True, check=False
        )
        lines += [f"  pip {args[0]}: {line}" for line in out.stdout.splitlines() if line.strip()]
    return "\n".join(lines)


def _copy_checkout(dest: pathlib.Path) -> None:
    archive = dest.with_suffix(".tar")
    subprocess.run(["git", "-C", str(ROOT), "archive", "-o", str(archive), "HEAD"], check=True)
    with tarfile.open(archive) as tar:
        if hasattr(tarfile, "data_filter"):
            tar.extractall(dest, filter="data")
        else:  # Python < 3.11.4; our own archive
            tar.extractall(dest)
    archive.unlink()


def _time_view(
    venv: pathlib.Path, log: pathlib.Path, timeout_s: float = 120.0
) -> tuple[float, float]:
    """Seconds from starting ``orientviz view`` until (a) 127.0.0.1 answers HTTP 200 and
    (b) the command prints its "open http://..." line, which it does after the default
    demo's scene is built (the server answers before that)."""
    port = _free_port()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    t = time.perf_counter()
    with open(log, "wb") as f:
        proc = subprocess.Popen(
            [str(venv / "bin" / "orientviz"), "view", "--port", str(port)],
            stdout=f, stderr=subprocess.STDOUT, env=env, cwd=venv.parent,
            start_new_session=True,
        )  # fmt: skip
    t_http = t_ready = None
    try:
        while time.perf_counter() - t < timeout_s and (t_http is None or t_ready is None):
            if proc.poll() is not None:
                raise RuntimeError(f"orientviz view exited {proc.returncode}:\n{log.read_text()}")
            if t_ready is None and f"open http://127.0.0.1:{port}" in log.read_text():
                t_ready = time.perf_counter() - t
            if t_http is None:
                try:
                    with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=2) as r:
                        if r.status == 200:
                            t_http = time.perf_counter() - t
                except OSError:
                    pass
            time.sleep(0.05)
        if t_http is None or t_ready is None:
            raise TimeoutError(
                f"orientviz view not ready within {timeout_s:.0f} s:\n{log.read_text()}"
            )
        return t_http, t_ready
    finally:
        os.killpg(proc.pid, signal.SIGINT)
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description="time the README's first command in a fresh venv")
    p.add_argument("--keep", action="store_true", help="keep the temporary directory")
    p.add_argument("--extra", default="viewer", help="the extra to install (default viewer)")
    args = p.parse_args(argv)
    print(f"checkout {ROOT} at {subprocess.getoutput(f'git -C {ROOT} rev-parse --short HEAD')}")
    print(f"python {sys.version.split()[0]} ({sys.executable}); load {os.getloadavg()}")
    print(_pip_environment())
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="orientviz-first-run-"))
    try:
        src, venv = tmp / "orientviz", tmp / "venv"
        _copy_checkout(src)
        t_venv = _run([sys.executable, "-m", "venv", str(venv)])
        pip = [str(venv / "bin" / "pip"), "install", "--quiet", "-e", f".[{args.extra}]"]
        env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
        t_install = _run(pip, cwd=src, env=env)
        t_http, t_ready = _time_view(venv, tmp / "view.log")
        total = t_venv + t_install + max(t_http, t_ready)
        verdict = "met" if total < GOAL_S else "MISSED"
        print(f"venv     {t_venv:7.1f} s   python -m venv")
        print(f'install  {t_install:7.1f} s   pip install -e ".[{args.extra}]" (in the venv)')
        print(f"http     {t_http:7.1f} s   orientviz view: first HTTP 200 on 127.0.0.1")
        print(f"ready    {t_ready:7.1f} s   orientviz view: demo built, URL printed")
        print(f"total    {total:7.1f} s   goal < {GOAL_S:.0f} s: {verdict}")
        print(f"load {os.getloadavg()}")
    finally:
        if args.keep:
            print(f"kept {tmp}")
        else:
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
