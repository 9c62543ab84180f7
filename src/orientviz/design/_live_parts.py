"""The parts of a live design (:mod:`orientviz.design._live`): the record of a control
change, the cofactor terms the shown quantities come from, the determinability checks a
changed design must pass (as the bundle's), the weights of given coordinates, and the
BLAS thread limit of its work.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import scipy.sparse
import scipy.sparse.csgraph
from numpy.typing import NDArray

from ..blas import blas_threads
from ..block import Block
from ..errors import NotDeterminableError

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class Change:
    """One change of a design: point ``point`` gets control σ ``sigma`` (m, NaN = that
    coordinate not given; all NaN = tie point); ``before`` is what it had."""

    point: int
    sigma: tuple[float, float, float]
    before: tuple[float, float, float]

    def describe(self, ids: list[str]) -> str:
        """The change in words."""

        def txt(s):
            s = np.asarray(s)
            if not np.isfinite(s).any():
                return "tie"
            return (
                "control σ " + "/".join("–" if not np.isfinite(v) else f"{v:g}" for v in s) + " m"
            )

        return f"point {ids[self.point]}: {txt(self.before)} → {txt(self.sigma)}"


def _capped(method):
    """Run a :class:`LiveDesign` method with its BLAS thread limit."""

    @functools.wraps(method)
    def run(self, *args, **kwargs):
        with blas_threads(self.blas_threads):
            return method(self, *args, **kwargs)

    return run


def _check_connected(block: Block) -> None:
    """Raise :class:`NotDeterminableError` if the images fall apart into groups that
    share no point (as the bundle does)."""
    O = block.observations
    m, p = block.n_images, block.n_points
    g = scipy.sparse.coo_matrix(
        (np.ones(O.image.size), (O.image, m + O.point)), shape=(m + p, m + p)
    )
    n, labels = scipy.sparse.csgraph.connected_components(g, directed=False)
    groups = np.unique(labels[:m])
    if groups.size > 1:
        raise NotDeterminableError(
            f"the changed design is not determinable: its images fall apart into "
            f"{groups.size} groups that share no point",
            parameters=[],
            defect=7 * (groups.size - 1),
        )


def _check_rays(block: Block) -> None:
    """Raise :class:`NotDeterminableError` for tie points seen in fewer than two images
    and images that see fewer than three points (the bundle's rule)."""
    O = block.observations
    rays = np.bincount(O.point, minlength=block.n_points)
    weak = np.flatnonzero((rays < 2) & ~np.isfinite(block.points.sigma).all(axis=1))
    few = np.flatnonzero(np.bincount(O.image, minlength=block.n_images) < 3)
    if weak.size or few.size:
        what = [f"point {block.points.ids[j]}" for j in weak[:4]]
        what += [f"image {block.images.ids[i]}" for i in few[:4]]
        raise NotDeterminableError(
            f"the design is not determinable: {weak.size} tie point(s) in fewer than two "
            f"images, {few.size} image(s) with fewer than three points ({', '.join(what)})",
            parameters=[],
        )


def check_structure(block: Block) -> None:
    """Raise :class:`NotDeterminableError` for a design block a live design cannot take:
    images that fall apart into groups sharing no point, tie points in fewer than two
    images, images with fewer than three points (the bundle's rules)."""
    _check_connected(block)
    _check_rays(block)


def _weights(sig) -> F64:
    s = np.asarray(sig, float)
    return np.where(np.isfinite(s), 1.0 / np.where(np.isfinite(s), s, 1.0) ** 2, 0.0)


@dataclass(frozen=True)
class _Current:
    """The cofactor terms the shown quantities come from: point blocks by base point,
    station blocks by image slot, ray terms by ray slot."""

    Qp: F64
    Qe: F64
    r: F64
    rxy: F64
    Ke: F64
    Kp: F64


def _aux_rows(rows, img_slot, pt_slot) -> dict:
    """Auxiliary rows by label: (on an image, target slot, coordinate, offset columns,
    their coefficients, weight 1/σ² in 1/m²); ``img_slot``/``pt_slot`` map the block's
    image/point index to the live design's slot."""
    if rows is None:
        return {}
    out = {}
    for i, label in enumerate(rows.labels):
        on = bool(rows.on_image[i])
        t = int(rows.target[i])
        out[label] = (
            on, int(img_slot(t) if on else pt_slot(t)), int(rows.coord[i]),
            tuple(int(v) for v in rows.gcol[i]), tuple(float(v) for v in rows.gcoef[i]),
            float(rows.w[i]),
        )  # fmt: skip
    return out


def _with_aux_rows(imgs, pts, G, d, removed: list, added: list):
    """Rows G (r, k) over image slots ``imgs``, points ``pts`` extended by auxiliary rows
    taken away (d = −1) and added (d = +1), each √w·(unit on its coordinate + the
    coefficients of its offsets): (image slots, points, offsets, G, d) with the columns
    [images · 6 | points · 3 | offsets]."""
    if not removed and not added:
        return imgs, pts, np.zeros(0, np.int64), G, d
    rows = [(v, -1.0) for v in removed] + [(v, 1.0) for v in added]
    extra_i = [v[1] for v, _ in rows if v[0] and v[1] not in set(imgs.tolist())]
    extra_p = [v[1] for v, _ in rows if not v[0] and v[1] not in set(pts.tolist())]
    imgs2 = np.r_[imgs, np.unique(np.asarray(extra_i, np.int64))].astype(np.int64)
    pts2 = np.r_[pts, np.unique(np.asarray(extra_p, np.int64))].astype(np.int64)
    gs = np.unique([c for v, _ in rows for c in v[3] if c >= 0]).astype(np.int64)
    ki, kp = 6 * imgs2.size, 3 * pts2.size
    G2 = np.zeros((G.shape[0] + len(rows), ki + kp + gs.size))
    G2[: G.shape[0], : 6 * imgs.size] = G[:, : 6 * imgs.size]
    G2[: G.shape[0], ki : ki + 3 * pts.size] = G[:, 6 * imgs.size :]
    pi = {int(s): t for t, s in enumerate(imgs2)}
    pp = {int(s): t for t, s in enumerate(pts2)}
    pg = {int(s): t for t, s in enumerate(gs)}
    for r, ((on, slot, c, gcol, gcoef, w), _) in enumerate(rows):
        row = G2[G.shape[0] + r]
        row[6 * pi[slot] + c if on else ki + 3 * pp[slot] + c] = np.sqrt(w)
        for gc, gf in zip(gcol, gcoef):
            if gc >= 0:
                row[ki + kp + pg[gc]] += np.sqrt(w) * gf
    return imgs2, pts2, gs, G2, np.r_[d, [sign for _, sign in rows]]
