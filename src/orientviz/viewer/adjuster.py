"""How the viewer adjusts a block and reads an :class:`Adjustment` back into a Block.

The viewer does not hold a solver of its own: blocks and demos are adjusted by
:func:`orientviz.bundle.bundle_adjust` (:func:`default_adjuster`), problem files by the
bundle with the file's model (:class:`orientviz.viewer.solved.FileAdjuster`).

Parameter layout (the bundle contract): block ``"exterior"`` (m, 6) with X0, Y0, Z0 in
m and ω, φ, κ in rad per image (the block's rotation sequence), block ``"points"``
(p, 3) with X, Y, Z in m.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..adjust import Adjustment
from ..block import Block
from ..bundle import bundle_adjust

#: ``adjuster(block, max_iter) -> Adjustment``; adjusters that can skip the precision
#: also take ``precision=False`` (the viewer's quick re-solve after an action).
Adjuster = Callable[..., Adjustment]


def apply_parameters(block: Block, result: Adjustment, x: np.ndarray | None = None) -> Block:
    """Copy of ``block`` with exterior orientations and points taken from ``x``.

    Parameters
    ----------
    block : Block
        The block the adjustment was computed for.
    result : Adjustment
        Supplies the parameter layout (``blocks["exterior"]``, ``blocks["points"]``).
    x : ndarray, optional
        A parameter vector in that layout (default ``result.x``), e.g. a history record.
    """
    x = result.x if x is None else np.asarray(x, dtype=float)
    out = block.copy()
    m, p = block.n_images, block.n_points
    if "exterior" in result.groups:
        ext = x[result.groups["exterior"]].reshape(m, 6)
        out.images.X0 = ext[:, :3].copy()
        out.images.angles = ext[:, 3:].copy()
    if "points" in result.groups:
        out.points.xyz = x[result.groups["points"]].reshape(p, 3).copy()
    return out


def default_adjuster() -> Adjuster:
    """The bundle to use: :func:`orientviz.bundle.bundle_adjust`."""

    def adjust(block: Block, max_iter: int, precision: bool = True) -> Adjustment:
        return bundle_adjust(block, max_iter=max_iter, history_x=True, precision=precision)

    return adjust


def image_normalized_residuals(result: Adjustment | None, n: int) -> np.ndarray | None:
    """Normalised residuals (n, 2) of the n image observations, or None if not available.

    Assumes the contract's order: the first 2n residuals are x, y of observation 0, 1, ….
    """
    if result is None or result.normalized_residuals is None:
        return None
    w = np.asarray(result.normalized_residuals)
    if w.shape[0] < 2 * n:
        return None
    return w[: 2 * n].reshape(n, 2)
