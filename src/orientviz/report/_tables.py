"""Per-image and per-point result tables of a block adjustment (and their CSV files).

:func:`image_table` and :func:`point_table` collect, for every image and point of a
block, the adjusted values, their a-posteriori standard deviations and the residuals of
the observations that belong to it: the tables one looks at to debug an adjustment
(which image has large residuals? which point is weakly determined?) and the ones
:func:`write_csv` exports. Without an adjustment the tables hold the block's values and
the misclosures at these values (no σ, no normalised residuals).

Units: object coordinates and their σ in m (a reconstruction without scale: labelled
``model``, values 1 : 1), angles and their σ in ``angle_unit`` (default gon), residuals in
µm (image; px for a file in pixels), ``max_w`` is the largest abs(normalised residual) w
of the item's observations (NaN where not available).
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..adjust.result import Adjustment
from ..block import ROLES, Block
from ..errors import InputError
from ..io.control import csv_rows
from ..io.safeio import open_input_text, write_atomic
from ..io.solve import adjusted_cameras
from ..units import from_rad

F64 = NDArray[np.float64]


@dataclass
class ResultTable:
    """Named columns of equal length, with the unit of each (``""`` for none).

    Attributes
    ----------
    name : str
        ``"images"`` or ``"points"``.
    columns : dict of str → ndarray
        The columns (ids as str arrays, numbers as floats/ints).
    units : dict of str → str
        Unit of each column.
    """

    name: str
    columns: dict[str, np.ndarray]
    units: dict[str, str]

    def __len__(self) -> int:
        return len(next(iter(self.columns.values())))

    def __getitem__(self, key: str) -> np.ndarray:
        return self.columns[key]

    def sorted_by(
        self, column: str, *, descending: bool = True, top: int | None = None
    ) -> ResultTable:
        """The rows ordered by ``column`` (NaN last), optionally only the first ``top``."""
        v = np.asarray(self.columns[column], dtype=float)
        key = np.where(np.isnan(v), -np.inf if descending else np.inf, v)
        order = np.argsort(-key if descending else key, kind="stable")[:top]
        return ResultTable(self.name, {k: c[order] for k, c in self.columns.items()}, self.units)

    def text(self, columns: list[str] | None = None, digits: int = 3) -> str:
        """A plain-text table of ``columns`` (default all)."""
        cols = columns or list(self.columns)
        head = [f"{c} [{self.units[c]}]" if self.units.get(c) else c for c in cols]
        cells = [[_fmt(self.columns[c][i], digits) for c in cols] for i in range(len(self))]
        width = [
            max(len(h), *(len(r[j]) for r in cells)) if cells else len(h)
            for j, h in enumerate(head)
        ]
        line = lambda r: "  ".join(s.rjust(w) for s, w in zip(r, width))
        return "\n".join([line(head)] + [line(r) for r in cells])

    def __str__(self) -> str:
        return self.text()

    def to_csv(self, path: str | os.PathLike[str]) -> Path:
        """Write the table as CSV (header ``name[unit]``; NaN as an empty cell), atomically."""
        import io

        fh = io.StringIO(newline="")
        w = csv.writer(fh)
        w.writerow(
            [f"{c}[{u}]" if u else c for c, u in ((c, self.units.get(c, "")) for c in self.columns)]
        )
        for i in range(len(self)):
            w.writerow([_cell(self.columns[c][i]) for c in self.columns])
        return write_atomic(path, fh.getvalue())


def _fmt(v, digits: int) -> str:
    if isinstance(v, str | np.str_):
        return str(v)
    if isinstance(v, int | np.integer):
        return str(int(v))
    return "—" if not np.isfinite(v) else f"{v:.{digits}f}"


def _cell(v) -> str:
    if isinstance(v, str | np.str_):
        return str(v)
    if isinstance(v, int | np.integer):
        return str(int(v))
    return "" if not np.isfinite(v) else repr(float(v))


def adjusted_block(block: Block, adj: Adjustment) -> Block:
    """Copy of ``block`` with the adjusted orientations, points and cameras (a lens
    model's estimates, :func:`~orientviz.io.solve.adjusted_cameras`) of a bundle result.

    Parameters
    ----------
    block : Block
        The block that was adjusted.
    adj : Adjustment
        Its bundle result (blocks ``"exterior"`` (m, 6) and ``"points"`` (p, 3)).
    """
    if "exterior" not in adj.groups:
        raise InputError("expected a bundle adjustment (parameter block 'exterior')")
    out = block.copy()
    ext = adj.x[adj.groups["exterior"]].reshape(block.n_images, 6)
    out.images.X0 = ext[:, :3].copy()
    out.images.angles = ext[:, 3:].copy()
    if "points" in adj.groups:
        xyz = adj.x[adj.groups["points"]].reshape(block.n_points, 3)
        ok = np.all(np.isfinite(xyz), axis=1)
        out.points.xyz = np.where(ok[:, None], xyz, block.points.xyz)
    adjusted_cameras(out, getattr(adj, "camera", None))
    return out


def _observation_stats(block: Block, adj: Adjustment | None) -> tuple[F64, F64]:
    """Residuals (n, 2) in µm and abs(w) (n,) per observation (NaN where not available)."""
    n = block.n_observations
    if adj is None:
        return -block.residuals() * 1000.0, np.full(n, np.nan)
    v = np.asarray(adj.residuals[: 2 * n], dtype=float).reshape(n, 2) * 1000.0
    w = adj.normalized_residuals
    if w is None or np.size(w) < 2 * n:
        return v, np.full(n, np.nan)
    w = np.abs(np.asarray(w[: 2 * n], dtype=float).reshape(n, 2))
    return v, np.fmax(w[:, 0], w[:, 1])


def _group(index: np.ndarray, count: int, v: F64, w: F64) -> tuple[np.ndarray, F64, F64, F64]:
    """Per group: number of observations, RMS of v_x and v_y, largest abs(w)."""
    n_obs = np.bincount(index, minlength=count)
    ok = np.all(np.isfinite(v), axis=1)
    k = np.bincount(index[ok], minlength=count)
    with np.errstate(invalid="ignore", divide="ignore"):
        rx = np.sqrt(np.bincount(index[ok], v[ok, 0] ** 2, minlength=count) / k)
        ry = np.sqrt(np.bincount(index[ok], v[ok, 1] ** 2, minlength=count) / k)
    mw = np.full(count, np.nan)
    fin = np.isfinite(w)
    np.fmax.at(mw, index[fin], w[fin])
    return n_obs, rx, ry, mw


def _std(adj: Adjustment | None, block_name: str, shape: tuple[int, int]) -> F64:
    if adj is None or block_name not in adj.groups:
        return np.full(shape, np.nan)
    return np.asarray(adj.std()[adj.groups[block_name]], dtype=float).reshape(shape)


def _units(length: str, pixel_mm: float | None) -> tuple[str, float, str]:
    """(length label, factor µm → residual unit, residual label): ``"model"`` for a
    reconstruction's model units (values 1 : 1), px for a pixel file, else m and µm."""
    label = "model" if length == "model" else "m"
    return (label, 1e-3 / pixel_mm, "px") if pixel_mm else (label, 1.0, "um")


def image_table(
    block: Block,
    adj: Adjustment | None = None,
    *,
    angle_unit: str = "gon",
    length: str = "m",
    pixel_mm: float | None = None,
) -> ResultTable:
    """One row per image: orientation, its σ, residuals of the image's observations.

    Parameters
    ----------
    block : Block
        The adjusted block (start values and observations).
    adj : Adjustment, optional
        Its bundle adjustment; None tabulates the block as it is (misclosures).
    angle_unit : str
        Unit of ω, φ, κ and their σ (see :mod:`orientviz.units`).
    length : str
        The file's length unit: ``"model"`` labels the coordinates of a reconstruction
        without scale (values unchanged), anything else m.
    pixel_mm : float, optional
        mm per pixel of a file in pixels: the residuals in px (default µm).

    Returns
    -------
    ResultTable
        Columns ``id strip n_obs X0 Y0 Z0 omega phi kappa sX0 sY0 sZ0 somega sphi skappa
        rms_vx rms_vy max_w``.
    """
    b = block if adj is None else adjusted_block(block, adj)
    m = b.n_images
    lu, vf, vu = _units(length, pixel_mm)
    v, w = _observation_stats(block, adj)
    n_obs, rx, ry, mw = _group(b.observations.image, m, v * vf, w)
    s = _std(adj, "exterior", (m, 6))
    ang = from_rad(b.images.angles, angle_unit)
    sang = from_rad(s[:, 3:], angle_unit)
    cols = {"id": np.array(b.images.ids, dtype=str), "strip": b.images.strip.copy(), "n_obs": n_obs}
    units = {"id": "", "strip": "", "n_obs": ""}
    for k, name in enumerate(("X0", "Y0", "Z0")):
        cols[name], units[name] = b.images.X0[:, k].copy(), lu
    for k, name in enumerate(("omega", "phi", "kappa")):
        cols[name], units[name] = ang[:, k], angle_unit
    for k, name in enumerate(("sX0", "sY0", "sZ0")):
        cols[name], units[name] = s[:, k], lu
    for k, name in enumerate(("somega", "sphi", "skappa")):
        cols[name], units[name] = sang[:, k], angle_unit
    cols.update(rms_vx=rx, rms_vy=ry, max_w=mw)
    units.update(rms_vx=vu, rms_vy=vu, max_w="")
    return ResultTable("images", cols, units)


def point_table(
    block: Block,
    adj: Adjustment | None = None,
    *,
    length: str = "m",
    pixel_mm: float | None = None,
) -> ResultTable:
    """One row per point: coordinates, their σ, residuals of the point's rays.

    ``length`` and ``pixel_mm`` as in :func:`image_table`.

    Returns
    -------
    ResultTable
        Columns ``id role n_rays X Y Z sX sY sZ rms_vx rms_vy max_w`` (m or model units,
        µm or px).
    """
    b = block if adj is None else adjusted_block(block, adj)
    p = b.n_points
    lu, vf, vu = _units(length, pixel_mm)
    v, w = _observation_stats(block, adj)
    n_obs, rx, ry, mw = _group(b.observations.point, p, v * vf, w)
    s = _std(adj, "points", (p, 3))
    cols = {
        "id": np.array(b.points.ids, dtype=str),
        "role": np.array([ROLES[r] for r in b.points.role], dtype=str),
        "n_rays": n_obs,
    }
    units = {"id": "", "role": "", "n_rays": ""}
    for k, name in enumerate("XYZ"):
        cols[name], units[name] = b.points.xyz[:, k].copy(), lu
    for k, name in enumerate(("sX", "sY", "sZ")):
        cols[name], units[name] = s[:, k], lu
    cols.update(rms_vx=rx, rms_vy=ry, max_w=mw)
    units.update(rms_vx=vu, rms_vy=vu, max_w="")
    return ResultTable("points", cols, units)


def read_csv_table(path: str | os.PathLike[str]) -> dict[str, list[str]]:
    """Read a CSV written by :meth:`ResultTable.to_csv` back as columns of strings.

    Header names keep their unit suffix (``"X0[m]"``). Raises :class:`InputError`
    naming the file and line for rows with the wrong number of cells.
    """
    source = str(path)
    rows = csv_rows(open_input_text(path, "a CSV table"), source)
    if not rows:
        raise InputError("empty CSV file, expected a header", source, "line 1")
    head = rows[0]
    for no, r in enumerate(rows[1:], start=2):
        if len(r) != len(head):
            raise InputError(f"expected {len(head)} cells, got {len(r)}", source, f"line {no}")
    return {h: [r[j] for r in rows[1:]] for j, h in enumerate(head)}
