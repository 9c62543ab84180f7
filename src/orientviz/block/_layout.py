"""Block layout: strips, models (pairs of consecutive images), footprints, control layouts.

Used by the simulator, the model methods (:mod:`orientviz.stereo_models`,
:mod:`orientviz.polynomial`), the plots and the viewer. Object frame in m, Z up;
rotations R = R_ω·R_φ·R_κ (the block's ``sequence``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..errors import InputError
from ._tables import Block

F64 = NDArray[np.float64]
CONTROL_LAYOUTS = ("perimeter", "chains", "full", "corners", "none")


@dataclass
class BlockLayout:
    """Strips and models of a block (used by plots, the viewer and the model methods).

    Attributes
    ----------
    strips : list of ndarray
        Image indices of each strip in flight order.
    models : ndarray of int, shape (n_models, 2)
        (left, right) image indices of the models: consecutive images of a strip.
    model_strip : ndarray of int, shape (n_models,)
        Strip index of each model.
    footprints : ndarray, shape (m, 4, 2)
        Ground corners (X, Y) in m of each image, projected to the mean point height.
    """

    strips: list[NDArray[np.int64]]
    models: NDArray[np.int64]
    model_strip: NDArray[np.int64]
    footprints: F64

    @property
    def n_models(self) -> int:
        return int(self.models.shape[0])


def _take(indices: list[int], every: int) -> list[int]:
    """Every ``every``-th entry of ``indices`` plus the last one."""
    sel = indices[:: max(1, every)]
    if indices and sel[-1] != indices[-1]:
        sel.append(indices[-1])
    return sel


def control_positions(
    n_cols: int,
    n_rows: int,
    layout: str,
    spacing: int,
    chain_spacing: int,
    row_step: int,
    kind: str,
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.bool_]]:
    """Grid cells (column, row) of the control points of a layout and their given coordinates.

    Parameters
    ----------
    n_cols, n_rows : int
        Size of the standard-point grid (columns = images per strip, rows = 2·strips + 1).
    layout : {"perimeter", "chains", "full", "corners", "none"}
        Control layout.
    spacing : int
        Perimeter (and "full") spacing in bases along the strips.
    chain_spacing : int
        Spacing i in bases of the height-control chains across the strips ("chains").
    row_step : int
        Spacing of control rows across the strips, in grid rows (≈ ``spacing`` bases).
    kind : {"xyz", "xy+z"}
        "xyz": every control point is full XYZ control. "xy+z": perimeter points are
        planimetric (XY) control, chain points height (Z) control.

    Returns
    -------
    cols, rows : ndarray of int
    given : ndarray of bool, shape (n, 3)
        Which of X, Y, Z are given per control point.
    """
    cols_all, rows_all = list(range(n_cols)), list(range(n_rows))
    last_c, last_r = n_cols - 1, n_rows - 1
    cells: dict[tuple[int, int], NDArray[np.bool_]] = {}

    def add(c: int, r: int, g) -> None:
        cells[(c, r)] = cells.get((c, r), np.zeros(3, bool)) | np.asarray(g, bool)

    xy_given = (True, True, kind == "xyz")
    if layout in ("perimeter", "chains"):
        for c in _take(cols_all, spacing):
            add(c, 0, xy_given)
            add(c, last_r, xy_given)
        for r in _take(rows_all, row_step):
            add(0, r, xy_given)
            add(last_c, r, xy_given)
    if layout == "chains":
        z_given = (kind == "xyz", kind == "xyz", True)
        for c in _take(cols_all, chain_spacing):
            for r in rows_all:
                add(c, r, z_given)
    elif layout == "full":
        for c in _take(cols_all, spacing):
            for r in _take(rows_all, row_step):
                add(c, r, (True, True, True))
    elif layout == "corners":
        for c in (0, last_c):
            for r in (0, last_r):
                add(c, r, (True, True, True))
    elif layout not in ("perimeter", "none"):
        raise InputError(f"control: expected one of {', '.join(CONTROL_LAYOUTS)}, got {layout!r}")
    keys = sorted(cells)
    cols = np.array([k[0] for k in keys], dtype=np.int64)
    rows = np.array([k[1] for k in keys], dtype=np.int64)
    given = np.array([cells[k] for k in keys], dtype=bool).reshape(-1, 3)
    return cols, rows, given


def block_layout(block: Block, height: float | None = None) -> BlockLayout:
    """Strips, models and image footprints of a block.

    Images of a strip (``images.strip``, −1 = none) are taken in index order, which is
    the flight order for simulated blocks; every pair of consecutive images of a strip is
    a model (left, right).

    Parameters
    ----------
    block : Block
        Any block with ``images.strip`` set.
    height : float, optional
        Height in m of the plane the footprints are projected to (default: the mean of
        the point heights).

    Returns
    -------
    BlockLayout
    """
    s = block.images.strip
    strips = [np.flatnonzero(s == k) for k in np.unique(s[s >= 0])]
    pairs = [np.stack([ix[:-1], ix[1:]], axis=1) for ix in strips if ix.size >= 2]
    models = np.concatenate(pairs) if pairs else np.zeros((0, 2), np.int64)
    model_strip = s[models[:, 0]] if models.size else np.zeros(0, np.int64)
    Z = float(np.mean(block.points.xyz[:, 2])) if height is None else float(height)
    cam = block.images.camera
    corners = np.stack(
        [block.cameras.format_mm[cam, 0] / 2, block.cameras.format_mm[cam, 1] / 2], axis=1
    )
    sign = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]], float)
    xy = corners[:, None, :] * sign[None]  # (m, 4, 2)
    vec = np.concatenate(
        [xy, -np.broadcast_to(block.cameras.c[cam][:, None, None], (len(cam), 4, 1))], axis=2
    )
    R = block.rotations()
    d = np.einsum("mij,mkj->mki", R, vec)
    X0 = block.images.X0
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = (Z - X0[:, None, 2]) / d[..., 2]
    foot = X0[:, None, :2] + lam[..., None] * d[..., :2]
    return BlockLayout(
        strips=strips, models=models.astype(np.int64), model_strip=model_strip, footprints=foot
    )
