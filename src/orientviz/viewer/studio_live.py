"""Structural changes of the studio's bundle design, applied when first needed.

With the independent-models method chosen the studio shows the models design of the
block (:class:`orientviz.design.LiveModels`), not the bundle's. A change of the
structure (images added, removed or moved, a cross strip) then needs the changed block
at once, but the bundle's update of it (:meth:`orientviz.design.LiveDesign.add_images`,
:meth:`~orientviz.design.LiveDesign.remove_images`) only when the bundle's quality is
asked for again (the method switched back, a control change, a suggestion).
:class:`PendingDesign` holds the live design before the changes, the changes and the
changed block (made by the same edits :func:`orientviz.design.add_images` /
:func:`orientviz.design.remove_images` the live design makes) and applies them to the
live design in order when :meth:`PendingDesign.apply` is called. The changed block is
checked at once as the live design checks it (images that fall apart into groups, tie
points in fewer than two images, images with fewer than three points).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..block import Block
from ..design import LiveDesign, add_images, check_structure, remove_images


class PendingDesign:
    """A :class:`~orientviz.design.LiveDesign` with structural changes not yet applied.

    Parameters
    ----------
    base : LiveDesign
        The live design before the changes (left as it is).
    ops : list of (str, tuple, dict)
        The changes: the live design's method (``"add_images"`` or ``"remove_images"``)
        and its arguments, in order.
    block : Block
        The block after the changes.
    auxiliary : list of Auxiliary
        The auxiliary data of the changed block (as the live design would hold them).
    """

    def __init__(self, base: LiveDesign, ops: list, block: Block, auxiliary: list) -> None:
        self.base, self.ops, self._block, self.auxiliary = base, ops, block, auxiliary
        self._applied: LiveDesign | None = None

    @property
    def block(self) -> Block:
        """The changed block (the applied live design's, once applied)."""
        return self._block if self._applied is None else self._applied.block

    def apply(self) -> LiveDesign:
        """The live design after the changes (computed once: the live design's updates,
        or new designs where it makes them)."""
        if self._applied is None:
            live = self.base
            for name, args, kwargs in self.ops:
                live = getattr(live, name)(*args, **kwargs)
            self._applied = live
        return self._applied


def deferred(live: LiveDesign | PendingDesign) -> PendingDesign:
    """``live`` as a pending design: the structural changes made to it wait until
    :meth:`PendingDesign.apply` (none yet for a live design)."""
    if isinstance(live, PendingDesign):
        return live
    return PendingDesign(live, [], live.block, list(live.auxiliary))


def _base_and_ops(live: LiveDesign | PendingDesign) -> tuple[LiveDesign, list]:
    if isinstance(live, PendingDesign):
        return live.base, list(live.ops)
    return live, []


def _aux_of_block(live: LiveDesign | PendingDesign, block: Block, auxiliary) -> list:
    """The auxiliary data the live design would hold for ``block`` (``auxiliary``: the
    data or a function of the block giving them)."""
    if not live.auxiliary:
        return []
    return list(auxiliary(block) if callable(auxiliary) else auxiliary)


def _checked(block: Block) -> Block:
    check_structure(block)
    return block


def images_added(
    live: LiveDesign | PendingDesign, X0: ArrayLike, angles: ArrayLike, *, strip=None,
    ids: list[str] | None = None, auxiliary: Any = None,
) -> LiveDesign | PendingDesign:  # fmt: skip
    """``live`` with images added (:meth:`orientviz.design.LiveDesign.add_images`'s
    arguments): updated now for a live design, not yet applied for a pending one."""
    if isinstance(live, LiveDesign):
        return live.add_images(X0, angles, strip=strip, ids=ids, auxiliary=auxiliary)
    base, ops = _base_and_ops(live)
    b = _checked(add_images(live.block, X0, angles, strip=strip, ids=ids))
    aux = _aux_of_block(live, b, auxiliary)
    kw = dict(strip=strip, ids=ids, auxiliary=auxiliary)
    return PendingDesign(base, ops + [("add_images", (X0, angles), kw)], b, aux)


def images_removed(
    live: LiveDesign | PendingDesign, images: ArrayLike, label: str | None = None, *,
    auxiliary: Any = None,
) -> LiveDesign | PendingDesign:  # fmt: skip
    """``live`` without some images (:meth:`orientviz.design.LiveDesign.remove_images`'s
    arguments): updated now for a live design, not yet applied for a pending one."""
    if isinstance(live, LiveDesign):
        return live.remove_images(images, label, auxiliary=auxiliary)
    base, ops = _base_and_ops(live)
    idx = np.asarray(images, np.int64).reshape(-1)
    b = _checked(remove_images(live.block, idx))
    aux = _aux_of_block(live, b, auxiliary)
    op = ("remove_images", (idx, label), dict(auxiliary=auxiliary))
    return PendingDesign(base, ops + [op], b, aux)
