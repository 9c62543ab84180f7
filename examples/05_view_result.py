"""05 — The 3D viewer on an adjusted block.

:func:`orientviz.view` starts the viser viewer on a block and its adjustment: camera
frustums per strip, tie/control/check points, rays, residual vectors (with an
exaggeration slider), error ellipsoids and an iteration scrubber that replays the
adjustment step by step. It listens on 127.0.0.1 only; open ``app.url`` in a browser.

This script also runs without a browser: it starts the viewer on any free port, writes
a static HTML snapshot of the scene (one self-contained file, no server needed), and
stops. Pass ``--serve`` to keep the viewer running until Ctrl-C.

Run: ``python examples/05_view_result.py [--serve]``
"""

import sys
import tempfile
from pathlib import Path

import numpy as np

import orientviz as ov


def main(serve: bool = False) -> None:
    sim = ov.simulate_block(2, 5, rng=np.random.default_rng(5), n_check=3)
    adj = ov.bundle_adjust(sim.block)
    print(adj.summary())

    app = ov.view((sim.block, adj), port=8080 if serve else 0, verbose=False)
    print(f"viewer running at {app.url}")
    if serve:
        app.wait()  # until Ctrl-C, then the server stops
        return
    try:
        with tempfile.TemporaryDirectory() as tmp:
            path = app.export_html(Path(tmp) / "block.html")
            size = path.stat().st_size
            head = path.read_text(encoding="utf-8")[:200].lower()
        print(f"static snapshot: {path.name}, {size / 1e6:.2f} MB, an HTML page: {'<html' in head}")
    finally:
        app.stop()
    print("viewer stopped")


if __name__ == "__main__":
    main(serve="--serve" in sys.argv[1:])
