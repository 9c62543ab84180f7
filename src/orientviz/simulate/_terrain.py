"""Smooth random terrain for simulated blocks (heights in m, object frame Z up)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

F64 = NDArray[np.float64]


class Terrain:
    """Smooth random hills: a sum of Gaussian bumps, scaled to a peak-to-peak relief.

    Parameters
    ----------
    rng : numpy.random.Generator
        Random numbers.
    extent : tuple of float
        (xmin, xmax, ymin, ymax) of the area in m.
    relief_m : float
        Peak-to-peak height range over ``extent`` in m (0 gives a plane).
    base_m : float
        Mean height (middle of the range) in m.
    """

    def __init__(self, rng, extent, relief_m: float, base_m: float, hills_per_km2=0.15):
        xmin, xmax, ymin, ymax = extent
        area_km2 = max((xmax - xmin) * (ymax - ymin) / 1e6, 1.0)
        n = int(min(max(8, round(hills_per_km2 * area_km2)), 4000))
        self.cx = rng.uniform(xmin, xmax, n)
        self.cy = rng.uniform(ymin, ymax, n)
        self.w = rng.uniform(700.0, 2500.0, n)
        self.a = rng.normal(0.0, 1.0, n)
        if relief_m <= 0:  # a plane at base_m (the hills are drawn all the same)
            self.scale, self.offset = 0.0, float(base_m)
            return
        gx, gy = np.meshgrid(np.linspace(xmin, xmax, 80), np.linspace(ymin, ymax, 80))
        self.scale, self.offset = 1.0, 0.0
        h = self._raw(gx.ravel(), gy.ravel())
        lo, hi = float(h.min()), float(h.max())
        self.scale = relief_m / max(hi - lo, 1e-12)
        self.offset = base_m - 0.5 * (hi + lo) * self.scale

    def _raw(self, x: F64, y: F64) -> F64:
        out = np.zeros(np.shape(x))
        for i in range(0, self.cx.size, 256):  # chunks keep memory small
            sl = slice(i, i + 256)
            d2 = (np.asarray(x)[..., None] - self.cx[sl]) ** 2 + (
                np.asarray(y)[..., None] - self.cy[sl]
            ) ** 2
            out += np.sum(self.a[sl] * np.exp(-0.5 * d2 / self.w[sl] ** 2), axis=-1)
        return out

    def __call__(self, x, y) -> F64:
        """Terrain height Z in m at (x, y) in m."""
        if self.scale == 0.0:
            return np.full(np.shape(x), self.offset)
        return self.offset + self.scale * self._raw(np.asarray(x, float), np.asarray(y, float))
