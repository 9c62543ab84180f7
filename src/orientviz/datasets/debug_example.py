"""A "real-looking" adjustment to debug: a COLMAP text model, a BAL file and control.

orientviz ships no real image blocks, so lesson 15 (debugging an adjustment) builds
one: a simulated aerial block (:func:`~orientviz.simulate.simulate_block`, c =
152 mm, 1 : 10 000, 5 µm noise) written out as files the way another program would
hand them over, with the faults a real job has:

* a few **blunders** — image coordinates off by 40-80 µm (4-8 pixels of 10 µm);
* one **badly placed image** — its pose in the file is turned by 200 gon about the
  vertical and shifted by a few hundred metres (a wrong registration), so the bundle
  cannot converge from it;
* **no control in the model** — COLMAP and BAL know none; the control coordinates come
  in a separate CSV keyed by POINT3D_ID (:mod:`orientviz.io.control`).

:func:`make_debug_example` writes ``colmap/`` (cameras.txt, images.txt, points3D.txt),
``block.bal`` and ``control.csv`` into a folder and returns their paths with the truth
(which observations are blunders, which image is misplaced, the true block) so that a
lesson can check the student's findings. Units: m, mm, rad; pixel size 0.01 mm.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..block import CONTROL, Block
from ..io.bal import write_bal
from ..io.colmap import write_colmap
from ..io.control import ControlPoints, write_control
from ..simulate import simulate_block

#: default seed: the same files every time
SEED = 2024


@dataclass
class DebugExample:
    """Paths of the written files and what is wrong in them.

    Attributes
    ----------
    colmap, bal, control : Path
        The COLMAP text folder, the BAL file, the control CSV.
    blunders : list of (str, str)
        (image id, point id) of the corrupted observations, ids as read from COLMAP.
    blunder_sizes_mm : ndarray, shape (k,)
        Length of each error vector in mm.
    bad_image : str
        Id of the misplaced image.
    truth : Block
        The block with true orientations and points (COLMAP's ids).
    """

    colmap: Path
    bal: Path
    control: Path
    blunders: list[tuple[str, str]]
    blunder_sizes_mm: np.ndarray
    bad_image: str
    truth: Block


def make_debug_example(
    directory: str | os.PathLike[str],
    *,
    rng: np.random.Generator | int = SEED,
    strips: int = 3,
    images_per_strip: int = 6,
    blunders: int = 4,
    bad_image: int | None = None,
) -> DebugExample:
    """Write the example files into ``directory`` (created if needed).

    Parameters
    ----------
    directory : path-like
        Target folder.
    rng : Generator or int
        Random numbers (geometry, noise, blunders).
    strips, images_per_strip : int
        Size of the block.
    blunders : int
        Number of corrupted image coordinates (40-80 µm).
    bad_image : int, optional
        Index of the misplaced image (default: the middle image of the middle strip).

    Returns
    -------
    DebugExample
    """
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    sim = simulate_block(
        strips, images_per_strip, rng=rng,
        gross={"count": blunders, "size_mm": (0.04, 0.08)},
    )  # fmt: skip
    block, truth = sim.block.copy(), sim.truth.copy()
    # COLMAP numbers its points: give both blocks the ids the COLMAP file will carry
    ids = [str(j + 1) for j in range(block.n_points)]
    block.points.ids, truth.points.ids = list(ids), list(ids)
    k = (strips // 2) * images_per_strip + images_per_strip // 2 if bad_image is None else bad_image
    block.images.angles[k, 2] += np.pi
    block.images.X0[k, :2] += (250.0, -180.0)
    ctrl = block.points.role == CONTROL
    control = ControlPoints(
        [ids[j] for j in np.flatnonzero(ctrl)],
        block.points.xyz_known[ctrl].copy(),
        np.zeros((int(ctrl.sum()), 3)),
        np.full(int(ctrl.sum()), CONTROL, np.int8),
    )
    # the files carry no control: every point is a tie point there
    block.points.role[:] = 0
    block.points.xyz_known[:] = np.nan
    write_colmap(block, d / "colmap", pixel_size_mm=0.01)
    write_bal(block, d / "block.bal", pixel_size_mm=0.01)
    write_control(d / "control.csv", control)
    g = sim.info["gross"]
    o = block.observations
    pairs = [(block.images.ids[o.image[j]], ids[o.point[j]]) for j in g["index"]]
    return DebugExample(
        colmap=d / "colmap",
        bal=d / "block.bal",
        control=d / "control.csv",
        blunders=pairs,
        blunder_sizes_mm=np.linalg.norm(np.asarray(g["error_mm"]), axis=1),
        bad_image=block.images.ids[k],
        truth=truth,
    )
