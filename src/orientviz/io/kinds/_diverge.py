"""What moved most in a block adjustment that did not converge, in the user's ids.

A diverging bundle usually has one cause that shows as a few images or points running
away from their approximate values: a wrong start, a gross error in the measurements of
one image, a point id given to two different points, control in another frame. The note
names them so that the user knows where to look.
"""

from __future__ import annotations

import numpy as np

from ...block import Block

#: How many images and points the note names.
SHOWN: int = 5


def divergence_note(block: Block, adj, m_per_length: float, length: str) -> str | None:
    """A note naming the images and points that moved most from their approximations.

    Parameters
    ----------
    block : Block
        The block as it entered the adjustment (approximate values in m, rad).
    adj : BlockAdjustment
        The result (``exterior`` (m, 6), ``points`` (p, 3)); nothing is said when it
        converged.
    m_per_length : float
        Metres per length unit of the file.
    length : str
        Name of that unit.

    Returns
    -------
    str or None
    """
    if adj.converged:
        return None
    parts = []
    if getattr(adj, "exterior", None) is not None:
        shift = np.linalg.norm(adj.exterior[:, :3] - block.images.X0, axis=1)
        turn = np.degrees(np.max(np.abs(_wrap(adj.exterior[:, 3:] - block.images.angles)), axis=1))
        order = _largest(shift)
        if order.size:
            parts.append(
                "images "
                + ", ".join(
                    f"{block.images.ids[i]} ({_num(shift[i] / m_per_length)} {length}, "
                    f"{_num(turn[i])}°)"
                    for i in order
                )
            )
    if getattr(adj, "points", None) is not None:
        move = np.linalg.norm(np.asarray(adj.points) - block.points.xyz, axis=1)
        order = _largest(move)
        if order.size:
            parts.append(
                "points "
                + ", ".join(
                    f"{block.points.ids[i]} ({_num(move[i] / m_per_length)} {length})"
                    for i in order
                )
            )
    if not parts:
        return None
    return (
        "NOT CONVERGED — moved most from the approximate values: "
        + "; ".join(parts)
        + ". Look there first: wrong approximate values, a gross error in those images' "
        "measurements, one id given to two different points, or control in another frame"
    )


def _largest(values: np.ndarray) -> np.ndarray:
    """Indices of the ``SHOWN`` largest finite values, largest first (non-finite first of all)."""
    v = np.where(np.isfinite(values), values, np.inf)
    order = np.argsort(-v, kind="stable")[:SHOWN]
    return order[v[order] > 0]


def _num(x: float) -> str:
    return f"{x:.4g}" if np.isfinite(x) else "undefined (NaN/inf)"


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2 * np.pi) - np.pi
