"""What a block adjustment returns, whatever the method: typed results.

:class:`BlockAdjustment` extends the engine's
:class:`~orientviz.adjust.result.Adjustment` by the block's own quantities in one shape
for every method (bundle, independent models, polynomials): the exterior orientations
(m, 6), all block points (p, 3), the check points and the auxiliary data's estimates.
``result["points"]`` and ``result["exterior"]`` give these arrays too.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..adjust.result import Adjustment

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


@dataclass(frozen=True)
class CheckPoints:
    """Check points: coordinates not used in the adjustment, compared afterwards.

    Attributes
    ----------
    index : ndarray of int, shape (k,)
        Block indices of the check points.
    ids : list of str
        Their ids.
    difference : ndarray, shape (k, 3)
        Adjusted (intersected) minus given coordinates, m (NaN where not determined).
    rms : ndarray, shape (3,)
        RMS of the differences in X, Y, Z over the determined points, m.
    """

    index: I64
    ids: list[str]
    difference: F64
    rms: F64


@dataclass(frozen=True)
class AuxiliaryEstimates:
    """Estimates of the auxiliary data's unknowns and their rows' residuals.

    Attributes
    ----------
    offsets : dict of str to ndarray
        Per kind (``"gnss"``, ``"statoscope"``, ``"apr"``): offset (and drift) per strip,
        shape (strips, dims, 1 or 2), m (drift: m over the strip).
    sigma : dict of str to ndarray
        Their standard deviations (a posteriori), same shapes, m.
    residuals : ndarray, shape (rows,)
        Residuals v of the auxiliary rows, m.
    labels : list of str
        A label per row.
    names : list of str
        Names of the offset/drift unknowns.
    redundancy : ndarray, shape (rows,) or None
        Redundancy numbers of the rows (with the precision).
    """

    offsets: dict[str, F64]
    sigma: dict[str, F64]
    residuals: F64
    labels: list[str]
    names: list[str] = field(default_factory=list)
    redundancy: F64 | None = None


@dataclass
class BlockAdjustment(Adjustment):
    """The result of a block adjustment (every method): the engine's result plus the block.

    Attributes
    ----------
    exterior : ndarray, shape (m, 6) or None
        X0, Y0, Z0 (m), ω, φ, κ (rad, the block's sequence) per image; None for methods
        that estimate no image orientation (polynomials).
    points : ndarray, shape (p, 3)
        All block points, m: adjusted tie points, control (fixed at its given value or
        adjusted), check points intersected afterwards; NaN where not determined.
    check_points : CheckPoints or None
        Differences at the check points (None without check points).
    auxiliary : AuxiliaryEstimates or None
        Offsets/drifts of GNSS / statoscope / APR data (None without them).
    adjusted : tuple of int or None
        (n, u) of the adjustment itself: its equations (observations that entered it and
        pseudo-observations) and unknowns, so that n − u is the redundancy. The
        ``n_observations``/``n_unknowns`` of :class:`Adjustment` count every reported
        residual and parameter instead (rays of check points, fixed points, …).
    """

    exterior: F64 | None = None
    points: F64 | None = None
    check_points: CheckPoints | None = None
    auxiliary: AuxiliaryEstimates | None = None
    adjusted: tuple[int, int] | None = None

    def __getitem__(self, key: str) -> Any:
        """``"points"`` (p, 3) and ``"exterior"`` (m, 6) as typed; else as :class:`Adjustment`."""
        if key == "points" and self.points is not None:
            return self.points
        if key == "exterior" and self.exterior is not None:
            return self.exterior
        return super().__getitem__(key)

    @property
    def check_rms(self) -> F64:
        """RMS of the check-point differences in X, Y, Z (m); NaN without check points."""
        return self.check_points.rms if self.check_points is not None else np.full(3, np.nan)


def check_points_of(block, xyz: F64) -> CheckPoints | None:
    """The check points of ``block`` compared with adjusted coordinates ``xyz`` (p, 3) m.

    Returns None if the block has no check points.
    """
    chk = np.flatnonzero(block.points.role == 2)
    if not chk.size:
        return None
    d = xyz[chk] - block.points.xyz_known[chk]
    good = np.isfinite(d).all(axis=1)
    rms = np.sqrt(np.mean(d[good] ** 2, axis=0)) if good.any() else np.full(3, np.nan)
    return CheckPoints(chk, [block.points.ids[i] for i in chk], d, rms)
