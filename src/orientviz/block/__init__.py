"""The block: cameras, images, points and image observations (and what describes them).

"Block" means one thing in orientviz: the set of images and points that are adjusted
together. This package holds its data model and what is computed from the data alone:

* :class:`Block` with its tables :class:`Cameras`, :class:`Images`, :class:`Points`,
  :class:`Observations` (structure of arrays; m, mm, rad) and the point roles
  :data:`TIE`, :data:`CONTROL`, :data:`CHECK`;
* :func:`block_layout` → :class:`BlockLayout` (strips, stereo models = consecutive
  image pairs of a strip, footprints) and :func:`control_positions`;
* :class:`Auxiliary` (GNSS / statoscope / APR observations with strip offsets);
* what a block adjustment returns, whatever the method: :class:`BlockAdjustment`
  (exterior (m, 6), points (p, 3), :class:`CheckPoints`, :class:`AuxiliaryEstimates`).

The adjustments live elsewhere: :mod:`orientviz.bundle`, :mod:`orientviz.stereo_models`,
:mod:`orientviz.polynomial`; approximations from scratch come from
:mod:`orientviz.approximate`, simulated blocks from :mod:`orientviz.simulate`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..faces import lazy_names
from ._tables import (
    CHECK,
    CONTROL,
    ROLES,
    TIE,
    Block,
    Cameras,
    Images,
    Observations,
    Points,
    check_array,
    check_image_points,
    check_points,
    index_ids,
)

__all__ = [
    "CHECK",
    "CONTROL",
    "CONTROL_LAYOUTS",
    "KINDS",
    "ROLES",
    "TIE",
    "Auxiliary",
    "AuxiliaryEstimates",
    "BlockAdjustment",
    "CheckPoints",
    "Block",
    "BlockLayout",
    "Cameras",
    "Images",
    "Observations",
    "Points",
    "block_layout",
    "check_array",
    "check_image_points",
    "check_points",
    "check_points_of",
    "control_positions",
    "index_ids",
    "strip_time",
]

#: Names loaded on first use: reading and writing a block's files needs its tables only,
#: not its layout, its auxiliary data or what an adjustment of it returns.
_LAZY = {
    "KINDS": "._auxiliary",
    "Auxiliary": "._auxiliary",
    "strip_time": "._auxiliary",
    "CONTROL_LAYOUTS": "._layout",
    "BlockLayout": "._layout",
    "block_layout": "._layout",
    "control_positions": "._layout",
    "AuxiliaryEstimates": "._result",
    "BlockAdjustment": "._result",
    "CheckPoints": "._result",
    "check_points_of": "._result",
}

__getattr__ = lazy_names(__name__, _LAZY, globals())


def __dir__() -> list[str]:
    return list(__all__)


if TYPE_CHECKING:  # for type checkers and editors; nothing is imported at run time
    from ._auxiliary import KINDS, Auxiliary, strip_time
    from ._layout import CONTROL_LAYOUTS, BlockLayout, block_layout, control_positions
    from ._result import AuxiliaryEstimates, BlockAdjustment, CheckPoints, check_points_of
