"""The iterate of a bundle adjustment: a frozen value, never stored in the problem."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class BundleState:
    """Current values of all unknowns of a bundle adjustment.

    Attributes
    ----------
    X0 : ndarray, shape (m, 3)
        Projection centres, m.
    angles : ndarray, shape (m, 3)
        ω, φ, κ, rad (the block's rotation sequence).
    xyz : ndarray, shape (p, 3)
        All block points, m (fixed points at their given values).
    ap : ndarray, shape (q,)
        Additional parameters, group-major (units of the set, e.g. µm).
    g : ndarray, shape (na,)
        Offsets/drifts of the auxiliary data, m (and m per strip length).
    """

    X0: F64
    angles: F64
    xyz: F64
    ap: F64
    g: F64 = field(default_factory=lambda: np.zeros(0))

    def flat(self) -> F64:
        """The parameter vector in the result's order: exterior (m·6), points (p·3), ap."""
        return np.concatenate(
            [np.hstack([self.X0, self.angles]).ravel(), self.xyz.ravel(), self.ap]
        )


def wrap(a: F64) -> F64:
    """Angles wrapped to [−π, π), rad."""
    return (a + np.pi) % (2 * np.pi) - np.pi
