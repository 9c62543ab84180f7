"""The parts of a live design (:mod:`orientviz.design._live`): the record of a control
change, the cofactor terms the shown quantities come from, the determinability checks a
changed design must pass (as the bundle's), the weights of given coordinates, and the
BLAS thread limit of its work.
"""

from __future__ import annotations

import contextlib
import functools
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse
import scipy.sparse.csgraph
from numpy.typing import NDArray

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


def blas_threads(n: int | None) -> Any:
    """A context running BLAS on ``n`` threads (threadpoolctl), or doing nothing (``n`` None
    or without threadpoolctl).

    A live design's step is many BLAS calls on matrices of a few hundred rows; on a machine
    whose cores are busy, OpenBLAS's worker threads wait for each other in every call
    (benchmarks/README.md, "design studio")."""
    if n is None:
        return contextlib.nullcontext()
    try:
        from threadpoolctl import threadpool_limits  # optional: the viewer's extra
    except ImportError:
        return contextlib.nullcontext()
    return threadpool_limits(limits=n, user_api="blas")


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
