"""A command whose standard output is closed early (``orientviz … | head -1``) runs to its
end: its files are written, its exit code is kept and nothing is called an internal error."""

from __future__ import annotations

import os
import subprocess
import sys

#: The command's own process (``main()`` without argv, as the console script runs it).
_RUN = (
    "import sys\n"
    "from orientviz.cli import main\n"
    "sys.argv = ['orientviz', *sys.argv[1:]]\n"
    "main()\n"
)


def test_an_import_whose_reader_left_writes_its_file_and_exits_0(tmp_path):
    out = tmp_path / "lb.json"
    p = subprocess.Popen(
        [sys.executable, "-c", _RUN, "import-bal", "ladybug", "-o", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        cwd=tmp_path,
        env=dict(os.environ, MPLBACKEND="Agg"),
    )
    p.stdout.close()  # the reader is gone before the first line
    err = p.stderr.read().decode()
    assert p.wait(timeout=300) == 0, err
    assert "internal error" not in err and "BrokenPipe" not in err
    assert out.stat().st_size > 1_000_000  # the whole problem file (Ladybug: ~6 MB)
