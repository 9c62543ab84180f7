"""The viewer's records of a block's states: :class:`Snapshot` (one state on the iteration
scrubber) and :class:`Change` (one entry of the list of changes, restorable exactly).

Units: object space m, angles rad (the block's rotation sequence).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..adjust import Adjustment
from .edits import Edits, Mapping

F64 = NDArray[np.float64]


@dataclass
class Snapshot:
    """One replayable state: orientations, points and the σ0 reported for it."""

    label: str
    X0: F64
    angles: F64
    xyz: F64
    sigma0: float
    #: the camera terms (the result's ``"additional"`` block) at this state, or None
    ap: F64 | None = None


@dataclass
class Change:
    """One entry of the list of changes: what was done and the state it led to.

    Attributes
    ----------
    label : str
        What the user did, e.g. ``"observation img3/pt12 off"``.
    sigma0 : float
        σ̂0 of the adjustment after the change (NaN before any adjustment).
    edits : Edits
        The switches and values after the change.
    X0, angles, xyz : ndarray
        Estimates after the change (m, rad, m).
    result : Adjustment or None
        The adjustment after the change (laid out for the whole block).
    history : list of Snapshot
        The iteration history at that moment, and ``cursor`` its position.
    """

    label: str
    sigma0: float
    edits: Edits
    X0: F64
    angles: F64
    xyz: F64
    result: Adjustment | None
    history: list[Snapshot]
    cursor: int
    at_result: bool
    mapping: Mapping | None
    ap: F64 | None = None
