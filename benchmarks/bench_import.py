"""Import time of the front door: ``import orientviz`` and a first script's names.

Goal (issue 16): ``import orientviz`` stays < 0.3 s and loads no plotting or GUI library;
the face's names load on first use. Printed, never asserted (tests/core/test_imports.py
asserts *which* modules load, not how long it takes).

Each case runs in a fresh interpreter with ``-X importtime``; the time is the sum of the
top-level imports the statement caused (µs → ms), leaving out those an empty
interpreter makes too (site, encodings, …), best and median of N runs. Peers in
the same run: ``import numpy`` (what any scientific script pays first) and ``import
scipy.sparse`` (what the solvers need).

Run:  python benchmarks/bench_import.py [--reps 7]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys

CASES = {
    "import numpy (peer)": "import numpy",
    "import scipy.sparse (peer)": "import scipy.sparse",
    "import orientviz": "import orientviz",
    "ov.resection": "import orientviz as ov; ov.resection",
    "ov.bundle_adjust": "import orientviz as ov; ov.bundle_adjust",
    "ov.view (not called)": "import orientviz as ov; ov.view",
    "every face name": "import orientviz as ov\nfor n in ov.__all__: getattr(ov, n)",
}


def _top_level(code: str) -> tuple[dict[str, int], int]:
    """Top-level imports of ``code`` in a fresh interpreter: name → cumulative µs; module count."""
    probe = code + "\nimport sys; print(len(sys.modules))"
    out = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", probe],
        capture_output=True,
        text=True,
        check=True,
        env=os.environ.copy(),
    )
    top: dict[str, int] = {}
    for line in out.stderr.splitlines():
        # "import time: self [us] | cumulative | imported package"; top level = no indent
        if not line.startswith("import time:") or "cumulative" in line:
            continue
        _, cumulative, name = line.split("|")
        if not name.startswith("  ") and name.strip():
            top[name.strip()] = int(cumulative)
    return top, int(out.stdout.strip().splitlines()[-1])


STARTUP = set(_top_level("pass")[0]) if __name__ == "__main__" else set()


def import_ms(code: str) -> tuple[float, int]:
    """Import time (ms) of ``code``: its top-level imports that an empty interpreter
    (``pass``: site, encodings, …) does not make; and the number of modules loaded."""
    top, n = _top_level(code)
    return sum(v for k, v in top.items() if k not in STARTUP) / 1000.0, n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=7)
    args = ap.parse_args()
    print(
        f"python {sys.version.split()[0]}, load average {os.getloadavg()[0]:.2f}, {args.reps} runs"
    )
    print(f"{'case':28s} {'best ms':>9s} {'median ms':>10s} {'modules':>8s}")
    base = None
    for label, code in CASES.items():
        runs = [import_ms(code) for _ in range(args.reps)]
        times = [t for t, _ in runs]
        best, med = min(times), statistics.median(times)
        if label.startswith("import numpy"):
            base = med
        ratio = f"  ({med / base:.2f} × numpy)" if base else ""
        print(f"{label:28s} {best:9.1f} {med:10.1f} {runs[0][1]:8d}{ratio}")


if __name__ == "__main__":
    main()
