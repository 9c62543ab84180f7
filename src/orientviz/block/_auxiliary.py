"""Auxiliary observations of a block: GNSS projection centres, statoscope heights, APR profiles.

Ackermann (1974, §19): statoscope and APR data (airborne profile recorder: radar clearance
below the aircraft plus statoscope height) cut the dependence of a block on height
control; today GNSS positions of the projection centres do the same. Each kind is
affected per strip by an unknown offset (and optionally a linear drift with time):

* **GNSS** — observed projection centres X0, Y0, Z0 (m) with σ;
* **statoscope** — observed flying heights Z0 relative to an isobaric surface;
* **APR** — terrain heights Z of ground points at the nadir of the images.

:class:`Auxiliary` only describes the data. The joint adjustment (rows, weights and
the offset/drift unknowns) is done by :func:`orientviz.bundle.bundle_adjust` or
:func:`orientviz.stereo_models.independent_models` with ``auxiliary=[...]``;
simulated data come from :func:`orientviz.simulate.simulate_auxiliary`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ._tables import Block

F64 = NDArray[np.float64]
#: The kinds of auxiliary data.
KINDS = ("gnss", "statoscope", "apr")

__all__ = ["KINDS", "Auxiliary", "strip_time"]


@dataclass
class Auxiliary:
    """One kind of auxiliary observations of a block.

    Attributes
    ----------
    kind : {"gnss", "statoscope", "apr"}
    index : ndarray of int
        Images (gnss, statoscope) or points (apr) observed.
    values : ndarray
        Observed X0 (k, 3) m (gnss), Z0 (k,) m (statoscope) or terrain Z (k,) m (apr).
    sigma : float
        σ of one observation (m), per coordinate.
    strip : ndarray of int
        Strip of each observation (the offset groups).
    time : ndarray
        Position along the strip (image order, 0 … 1) for the drift.
    drift : bool
        Estimate a linear drift per strip besides the offset.
    offsets : bool
        Estimate offsets at all (False: the data are taken as absolute).
    """

    kind: str
    index: NDArray[np.int64]
    values: F64
    sigma: float
    strip: NDArray[np.int64]
    time: F64
    drift: bool = False
    offsets: bool = True
    truth: dict = field(default_factory=dict)


def strip_time(block: Block) -> F64:
    """Position of every image along its strip, 0 … 1 in image order (the drift's time)."""
    t = np.zeros(block.n_images)
    for s in np.unique(block.images.strip):
        ix = np.flatnonzero(block.images.strip == s)
        t[ix] = np.linspace(0.0, 1.0, ix.size) if ix.size > 1 else 0.0
    return t
