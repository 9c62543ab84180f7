"""Bookkeeping of model blocks: tie points, control coordinates, datum and connectivity checks.

Used by :mod:`orientviz.stereo_models` (independent models) and
:mod:`orientviz.polynomial` (strips). Object coordinates in m.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.csgraph import connected_components

from ..block import CHECK, CONTROL, Block
from ..errors import DatumDefectError, InputError

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


@dataclass
class TieSetup:
    """Rows (model, tie point, model coordinates) and the coordinate unknowns.

    The tie table holds the used block points (``tie_points``) followed by the projection
    centres of ``centre_images``. ``scalar[t, c]`` is the index of the unknown for
    coordinate c of tie point t, or −1 where the coordinate is fixed control.
    """

    tie_points: I64
    centre_images: I64
    point_names: list[str]
    row_model: I64
    row_point: I64
    m: F64
    X: F64
    known: F64
    scalar: I64
    prior_w: F64
    n_models: int
    model_ids: list[str]
    model_size: F64
    model_centroid: F64
    given: NDArray[np.bool_] = field(default_factory=lambda: np.zeros((0, 3), bool))

    @property
    def n_scalar(self) -> int:
        return int(self.prior_w.size)

    @property
    def redundancy(self) -> int:
        return int(
            3 * self.row_model.size + np.sum(self.prior_w > 0) - 7 * self.n_models - self.n_scalar
        )

    def prior_e(self) -> F64:
        """Current misclosures X − X_given of the weighted control coordinates (0 elsewhere)."""
        e = np.zeros(self.n_scalar)
        has = self.scalar >= 0
        diff = np.where(np.isnan(self.known), 0.0, self.X - np.nan_to_num(self.known))
        e[self.scalar[has]] = diff[has]
        return np.where(self.prior_w > 0, e, 0.0)

    def sub(self, coords: tuple[int, ...], rows=None) -> tuple[I64, int, I64]:
        """Numbering of the unknowns of some coordinates only (e.g. planimetry (0, 1)).

        Only tie points that occur in ``rows`` (a boolean mask of the rows; default all)
        are numbered. Returns the map (nt, len(coords)) to sub-indices (−1 fixed or not
        numbered), their number and the global scalar index of every sub-index.
        """
        g = self.scalar[:, list(coords)]
        occurs = np.zeros(g.shape[0], bool)
        occurs[self.row_point if rows is None else self.row_point[rows]] = True
        has = (g >= 0) & occurs[:, None]
        sub = np.full(g.shape, -1, np.int64)
        sub[has] = np.arange(int(has.sum()))
        return sub, int(has.sum()), g[has]

    def apply(self, dX: F64, coords: tuple[int, ...] = (0, 1, 2)) -> None:
        """Add corrections of the scalar unknowns (only those of ``coords``)."""
        for c in coords:
            has = self.scalar[:, c] >= 0
            self.X[has, c] += dX[self.scalar[has, c]]

    def init_points(self, lam: F64, R: F64, T: F64) -> None:
        """Start values of the free coordinates: mean of the transformed model coordinates."""
        j = self.row_model
        P = lam[j, None] * np.einsum("nij,nj->ni", R[j], self.m) + T[j]
        cnt = np.bincount(self.row_point, minlength=self.X.shape[0]).astype(float)
        for c in range(3):
            mean = np.bincount(self.row_point, P[:, c], minlength=self.X.shape[0]) / cnt
            free = ~self.given[:, c] | np.isnan(self.known[:, c])
            self.X[free, c] = mean[free]

    def param_names(self, p: int, labels: tuple[str, ...] | None = None) -> list[str]:
        labels = labels or ("rx", "ry", "rz", "scale", "X0", "Y0", "Z0")[:p]
        return [f"{mid}.{lab}" for mid in self.model_ids for lab in labels]

    def model_mean_z(self, lam: F64, R: F64, T: F64) -> F64:
        """Height (m) of each model's centroid after the current transformation."""
        return (lam[:, None] * np.einsum("nij,nj->ni", R, self.model_centroid) + T)[:, 2]

    def model_centre(self, P: F64) -> F64:
        """Mean (n, 3) of the transformed rows of each model."""
        cnt = np.bincount(self.row_model, minlength=self.n_models).astype(float)
        return np.column_stack(
            [np.bincount(self.row_model, P[:, c], minlength=self.n_models) / cnt for c in range(3)]
        )

    def block_coordinates(self, block: Block, ms, lam: F64, R: F64, T: F64) -> tuple[F64, F64]:
        """Adjusted coordinates of all block points (p, 3) and projection centres (m, 3).

        Tie points take their adjusted values; other points seen in models (check points)
        the mean of their transformed model coordinates; NaN for points in no model.
        """
        xyz = np.full((block.n_points, 3), np.nan)
        j = ms.point_model
        P = lam[j, None] * np.einsum("nij,nj->ni", R[j], ms.xyz) + T[j]
        cnt = np.bincount(ms.point, minlength=block.n_points).astype(float)
        with np.errstate(invalid="ignore", divide="ignore"):
            for c in range(3):
                xyz[:, c] = np.bincount(ms.point, P[:, c], minlength=block.n_points) / cnt
        xyz[self.tie_points] = self.X[: self.tie_points.size]
        centres = np.full((block.n_images, 3), np.nan)
        centres[self.centre_images] = self.X[self.tie_points.size :]
        return xyz, centres


def tie_setup(block: Block, ms, *, control: str = "fixed", use_centres: bool = True) -> TieSetup:
    """Collect the rows and unknowns of a model block.

    Parameters
    ----------
    block : Block
        Points with roles and given coordinates (``xyz_known``, ``sigma``).
    ms : ModelSet
        The models.
    control : {"fixed", "weighted"}
        "fixed": every given control coordinate is held fixed; "weighted": coordinates
        with σ > 0 become pseudo-observations (σ = 0 stays fixed).
    use_centres : bool
        Add the projection centres as tie points.
    """
    if control not in ("fixed", "weighted"):
        raise InputError(f"control: expected 'fixed' or 'weighted', got {control!r}")
    pts = block.points
    use = pts.role[ms.point] != CHECK
    tie = np.unique(ms.point[use])
    tie_of = np.full(block.n_points, -1, np.int64)
    tie_of[tie] = np.arange(tie.size)
    rm = [ms.point_model[use]]
    rp = [tie_of[ms.point[use]]]
    mm = [ms.xyz[use]]
    centres = np.zeros(0, np.int64)
    if use_centres:
        centres = np.unique(ms.models.ravel())
        cen_of = np.full(block.n_images, -1, np.int64)
        cen_of[centres] = tie.size + np.arange(centres.size)
        for side in (0, 1):
            rm.append(np.arange(ms.n_models))
            rp.append(cen_of[ms.models[:, side]])
            mm.append(ms.centres[:, side])
    row_model, row_point, m = np.concatenate(rm), np.concatenate(rp), np.concatenate(mm)
    order = np.argsort(row_model, kind="stable")
    row_model, row_point, m = row_model[order], row_point[order], m[order]
    nt = tie.size + centres.size
    known = np.full((nt, 3), np.nan)
    sig = np.full((nt, 3), np.nan)
    is_ctrl = pts.role[tie] == CONTROL
    known[: tie.size][is_ctrl] = pts.xyz_known[tie][is_ctrl]
    sig[: tie.size][is_ctrl] = pts.sigma[tie][is_ctrl]
    given = ~np.isnan(known)
    fixed = given & ((control == "fixed") | (np.nan_to_num(sig, nan=0.0) == 0))
    weighted = given & ~fixed
    scalar = np.full((nt, 3), -1, np.int64)
    scalar[~fixed] = np.arange(int(np.sum(~fixed)))
    prior_w = np.zeros(int(np.sum(~fixed)))
    prior_w[scalar[weighted]] = 1.0 / sig[weighted] ** 2
    X = np.where(given, known, 0.0)
    cnt = np.bincount(row_model, minlength=ms.n_models).astype(float)
    cent = np.column_stack(
        [np.bincount(row_model, m[:, c], minlength=ms.n_models) for c in range(3)]
    )
    cent /= cnt[:, None]
    size = np.sqrt(
        np.bincount(row_model, np.sum((m - cent[row_model]) ** 2, axis=1), minlength=ms.n_models)
        / cnt
    )
    names = [pts.ids[i] for i in tie] + [f"pc:{block.images.ids[i]}" for i in centres]
    return TieSetup(
        tie_points=tie, centre_images=centres, point_names=names, row_model=row_model,
        row_point=row_point, m=m, X=X, known=known, scalar=scalar, prior_w=prior_w,
        n_models=ms.n_models, model_ids=list(ms.ids), model_size=size, model_centroid=cent,
        given=given,
    )  # fmt: skip


def _describe(ids: list[str], members: I64) -> str:
    if members.size <= 2:
        return ", ".join(ids[k] for k in members)
    return f"{members.size} models {ids[members[0]]} … {ids[members[-1]]}"


def check_datum(su: TieSetup, ms, *, need_xy: bool = True, need_z: bool = True) -> None:
    """Raise :class:`DatumDefectError` if a connected part of the block lacks a datum.

    A part (models connected through shared tie points) needs ≥ 2 planimetric control
    points (``need_xy``) and ≥ 3 height control points not on one line (``need_z``).
    The message names the parts and what they lack.
    """
    n, nt = su.n_models, su.X.shape[0]
    A = sp.coo_matrix((np.ones(su.row_model.size), (su.row_model, su.row_point)), shape=(n, nt))
    A = sp.csr_matrix(A)
    n_parts, label = connected_components(A @ A.T, directed=False)
    xy_ok = su.given[:, 0] & su.given[:, 1]
    z_ok = su.given[:, 2]
    problems = []
    for k in range(n_parts):
        members = np.flatnonzero(label == k)
        pts = np.unique(su.row_point[np.isin(su.row_model, members)])
        nxy = int(np.sum(xy_ok[pts]))
        zp = pts[z_ok[pts]]
        lacks = []
        if need_xy and nxy < 2:
            lacks.append(f"{nxy} planimetric control point(s), needs ≥ 2")
        if need_z:
            xy = su.X[zp, :2] if zp.size else np.zeros((0, 2))
            spread = np.linalg.matrix_rank(xy - xy.mean(axis=0), tol=1.0) if zp.size >= 3 else 0
            if zp.size < 3 or spread < 2:
                lacks.append(f"{zp.size} height control point(s), needs ≥ 3 not on one line")
        if lacks:
            problems.append(
                f"part {k + 1} ({_describe(su.model_ids, members)}) has " + "; ".join(lacks)
            )
    if not problems:
        return
    if n_parts > 1:
        parts = "; ".join(
            f"part {k + 1}: {_describe(su.model_ids, np.flatnonzero(label == k))}"
            for k in range(n_parts)
        )
        raise DatumDefectError(
            f"the block falls apart into {n_parts} unconnected parts ({parts}); "
            + "; ".join(problems),
            parameters=[f"part {k + 1}" for k in range(n_parts)],
        )
    raise DatumDefectError("datum defect: the block " + problems[0].split(") has ", 1)[1])
