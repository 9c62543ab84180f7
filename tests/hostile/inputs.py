"""Small valid inputs of every format, built once per session (nothing committed).

:func:`base` returns the texts; a case writes them (or a mutation of them) into its own
folder. The block is a 1 × 5 simulated strip with full control (seeded): a problem file
(readable and columnar), a BAL file, a COLMAP text model and a control CSV keyed by its
point ids, plus the shipped resection/intersection/similarity/pair examples.
"""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path

BLOCK = "block.json"
COLMAP_BIN = "sparse_bin"
MARKS = "marks.csv"
COLUMNAR = "columnar.json"
BAL = "block.bal"
COLMAP = "sparse"
CONTROL = "control.csv"


@cache
def base() -> dict[str, str]:
    """name → text of each valid input (COLMAP files as ``sparse/<file>``)."""
    import tempfile

    from orientviz.block import CONTROL as ROLE_CONTROL
    from orientviz.io.bal import write_bal
    from orientviz.io.colmap import write_colmap
    from orientviz.io.control import ControlPoints, write_control
    from orientviz.io.datasets import dataset_path
    from orientviz.io.problem import dumps_problem, problem_from_block
    from orientviz.simulate import simulate_block

    sim = simulate_block(1, 5, rng=7, control="full")
    block = sim.block
    out = {
        BLOCK: dumps_problem(problem_from_block(block, columnar=False)),
        COLUMNAR: dumps_problem(problem_from_block(block, columnar=True)),
    }
    for name in ("resection_example", "intersection_example", "similarity_example"):
        out[f"{name}.json"] = dataset_path(name).read_text(encoding="utf-8")
    pair = Path(dataset_path("block_strip")).parents[1] / "pair" / "pair_example.json"
    out["pair_example.json"] = pair.read_text(encoding="utf-8")
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        free = block.copy()
        free.points.role[:] = 0
        write_bal(free, t / BAL)
        out[BAL] = (t / BAL).read_text()
        ids = [int(p) for p in range(1, free.n_points + 1)]
        free.points.ids = [str(i) for i in ids]
        write_colmap(free, t / COLMAP)
        for f in ("cameras.txt", "images.txt", "points3D.txt"):
            out[f"{COLMAP}/{f}"] = (t / COLMAP / f).read_text()
        obs = free.observations
        out[MARKS] = "image,point,x,y\n" + "".join(
            f"{free.images.ids[i]},{free.points.ids[j]},{x:.6f},{y:.6f}\n"
            for i, j, (x, y) in zip(obs.image, obs.point, obs.xy)
        )
        ctl = [i for i in range(block.n_points) if block.points.role[i] == ROLE_CONTROL]
        cp = ControlPoints(
            [str(i + 1) for i in ctl],
            sim.truth.points.xyz[ctl],
            sim.truth.points.xyz[ctl] * 0,
            block.points.role[ctl],
        )
        write_control(t / CONTROL, cp)
        out[CONTROL] = (t / CONTROL).read_text()
    return out


@cache
def base_binary() -> dict[str, bytes]:
    """The COLMAP model of :func:`base` in COLMAP's binary layout (``sparse_bin/<file>``)."""
    import tempfile

    from orientviz.io.colmap_bin import write_binary_model
    from orientviz.io.colmap_text_model import read_text_model

    texts = base()
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        (t / COLMAP).mkdir()
        for f in ("cameras.txt", "images.txt", "points3D.txt"):
            (t / COLMAP / f).write_text(texts[f"{COLMAP}/{f}"])
        write_binary_model(read_text_model(t / COLMAP), t / COLMAP_BIN)
        return {
            f"{COLMAP_BIN}/{f}": (t / COLMAP_BIN / f).read_bytes()
            for f in ("cameras.bin", "images.bin", "points3D.bin")
        }


def write_binary(folder: Path) -> None:
    """Write the binary COLMAP model into ``folder/sparse_bin``."""
    for name, data in base_binary().items():
        p = folder / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_bytes(data)


def write(folder: Path, *names: str, **replace: str) -> None:
    """Write the named base inputs into ``folder`` (``replace``: name → other text;
    keys with ``/`` are given as ``__``, e.g. ``sparse__cameras_txt``)."""
    texts = base()
    repl = {k.replace("__", "/").replace("_txt", ".txt"): v for k, v in replace.items()}
    for name in names:
        paths = [n for n in texts if n == name or n.startswith(name + "/")]
        for n in paths:
            p = folder / n
            p.parent.mkdir(parents=True, exist_ok=True)
            p.write_text(repl.get(n, texts[n]), encoding="utf-8")


def doc(name: str = BLOCK) -> dict:
    """The parsed JSON of a base problem file."""
    return json.loads(base()[name])
