"""Quality of each image and point of an adjusted block, for colouring the viewer's scene.

Plain numpy, no viser: the measures come from a bundle result (:class:`~orientviz.bundle.
BundleResult` or any :class:`~orientviz.adjust.Adjustment` with the bundle's residual
order: x, y of each image observation first) and the block it belongs to.

Measures (key → what it is, per image over its rays and per point over its rays):

* ``"rms_v"`` — RMS of the residuals in units of their a-priori σ, v/σ, of the image
  coordinates used; unitless, larger is worse. Needs no precision (large blocks open
  without it).
* ``"rms_w"`` — RMS of the normalised residuals w = v / (σ √r) of the image
  coordinates (Baarda, a-priori σ0 = 1); unitless, larger is worse.
* ``"max_w"`` — the largest abs(w); unitless, larger is worse.
* ``"redundancy"`` — the redundancy share: the mean redundancy number r_i of the
  image coordinates (0 … 1; the share of each observation that the others check);
  smaller is worse (an observation with r ≈ 0 is not controlled).
* ``"std"`` — standard deviation of the position: σ̂0 √(trace C / 3) with C the
  3 × 3 cofactor block of the projection centre (images) or of the point (points);
  m, larger is worse.

Observations that were not adjusted (switched off, rays of check points) have w and r
NaN and do not count; an image or point without any counted value gets NaN (drawn grey).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .shapes import ramp

F64 = NDArray[np.float64]

#: key → (label, unit, larger is worse)
MEASURES: dict[str, tuple[str, str, bool]] = {
    "rms_v": ("RMS of residuals |v|/σ (no precision needed)", "", True),
    "rms_w": ("RMS of normalised residuals |w|", "", True),
    "max_w": ("largest normalised residual |w|", "", True),
    "redundancy": ("redundancy share (mean r_i)", "", False),
    "std": ("standard deviation of the position", "m", True),
}

#: The quality ramp: good (blue-green) → fair (yellow) → bad (red), readable on white.
STOPS = np.array([[40, 110, 190], [40, 170, 120], [235, 190, 30], [215, 40, 40]], float)

#: Upper end of the colour scale of the abs(w) measures (W_CRITICAL ≈ 3.29 sits near red).
W_SCALE: float = 4.0


@dataclass(frozen=True)
class Quality:
    """One measure per image and per point, with the scale it is coloured on.

    Attributes
    ----------
    key, label, unit : str
        The measure (see :data:`MEASURES`).
    worse_high : bool
        True if larger values are worse.
    image : ndarray, shape (m,)
        Value per image (NaN: not available).
    point : ndarray, shape (p,)
        Value per point (NaN: not available).
    lo, hi : float
        The values mapped to the first and the last colour of the ramp.
    """

    key: str
    label: str
    unit: str
    worse_high: bool
    image: F64
    point: F64
    lo: float
    hi: float

    def badness(self, values: F64) -> F64:
        """Position of ``values`` on the scale, 0 (good) … 1 (bad), NaN stays NaN."""
        t = (np.asarray(values, float) - self.lo) / max(self.hi - self.lo, 1e-300)
        t = np.clip(t, 0.0, 1.0)
        return t if self.worse_high else 1.0 - t

    def colours(self, values: F64) -> NDArray[np.uint8]:
        """RGB (k, 3) uint8 of ``values`` on the ramp (NaN grey)."""
        return ramp(self.badness(values), 1.0, STOPS)

    def worst(self, which: str, k: int = 10) -> NDArray[np.int64]:
        """Indices of the ``k`` worst images (``which="image"``) or points, worst first."""
        v = self.image if which == "image" else self.point
        ok = np.flatnonzero(np.isfinite(v))
        key = -v[ok] if self.worse_high else v[ok]
        return ok[np.argsort(key, kind="stable")[:k]]

    def ticks(self, n: int = 3) -> list[float]:
        """``n`` values evenly spaced from the good end of the scale to the bad end."""
        a, b = (self.lo, self.hi) if self.worse_high else (self.hi, self.lo)
        return [float(x) for x in np.linspace(a, b, n)]


def image_observation_arrays(result, n: int) -> tuple[F64, F64]:
    """Normalised residuals and redundancy numbers (n, 2) of the n image observations.

    NaN where the result has none (no precision computed, ray not adjusted).
    """
    nan = np.full((n, 2), np.nan)
    if result is None:
        return nan, nan.copy()
    out = []
    for arr in (result.normalized_residuals, result.redundancy_numbers):
        a = None if arr is None else np.asarray(arr, float)
        out.append(a[: 2 * n].reshape(n, 2).copy() if a is not None and a.size >= 2 * n else nan)
    return out[0], out[1]


def image_v_sigma(block, result) -> F64:
    """v/σ (n, 2) of the image coordinates the result used (NaN for the others, or all
    NaN without a result)."""
    n = block.n_observations
    v = None if result is None else np.asarray(result.residuals, float)
    if v is None or v.size < 2 * n:
        return np.full((n, 2), np.nan)
    out = v[: 2 * n].reshape(n, 2) / block.observations.sigma
    used = getattr(result, "used_obs", None)
    if used is not None and np.size(used) == n:
        out[~np.asarray(used, bool)] = np.nan
    return out


def _group(index: NDArray[np.int64], values: F64, size: int) -> tuple[F64, F64, F64, F64]:
    """Per group: count of finite values, their sum of squares, their sum, max of abs."""
    ok = np.isfinite(values)
    idx = np.repeat(index, values.shape[1])[ok.reshape(-1)]
    v = values.reshape(-1)[ok.reshape(-1)]
    cnt = np.bincount(idx, minlength=size).astype(float)
    sq = np.bincount(idx, weights=v * v, minlength=size)
    s = np.bincount(idx, weights=v, minlength=size)
    mx = np.full(size, -np.inf)
    np.maximum.at(mx, idx, np.abs(v))
    return cnt, sq, s, mx


def position_std(cofactors: F64 | None, sigma0: float, count: int, first: int = 0) -> F64:
    """σ̂0 √(trace C / 3) (m) from stacked cofactor blocks; ``first`` = row of X in a block."""
    if cofactors is None or np.shape(cofactors)[0] != count:
        return np.full(count, np.nan)
    Q = np.asarray(cofactors, float)[:, first : first + 3, first : first + 3]
    with np.errstate(invalid="ignore"):
        return sigma0 * np.sqrt(np.clip(np.einsum("nii->n", Q), 0.0, None) / 3.0)


def compute_quality(block, result, key: str) -> Quality:
    """Measure ``key`` (see :data:`MEASURES`) per image and per point.

    Parameters
    ----------
    block : Block
        The block the result belongs to (its observations index images and points).
    result : Adjustment or None
        The adjustment (residual order of the bundle). None gives NaN everywhere.
    key : str
        ``"rms_v"``, ``"rms_w"``, ``"max_w"``, ``"redundancy"`` or ``"std"``.

    Raises
    ------
    KeyError
        For an unknown measure.
    """
    label, unit, worse_high = MEASURES[key]
    m, p, n = block.n_images, block.n_points, block.n_observations
    o = block.observations
    w, r = image_observation_arrays(result, n)
    per = {}
    if key in ("rms_v", "rms_w", "max_w", "redundancy"):
        vals = {"redundancy": r, "rms_v": image_v_sigma(block, result)}.get(key, w)
        for name, index, size in (("image", o.image, m), ("point", o.point, p)):
            cnt, sq, s, mx = _group(index, vals, size)
            with np.errstate(invalid="ignore", divide="ignore"):
                if key in ("rms_w", "rms_v"):
                    v = np.sqrt(sq / cnt)
                elif key == "max_w":
                    v = np.where(cnt > 0, mx, np.nan)
                else:
                    v = s / cnt
            per[name] = np.where(cnt > 0, v, np.nan)
        lo, hi = (0.0, W_SCALE) if key != "redundancy" else (0.0, 1.0)
    else:
        s0 = 1.0
        if result is not None and np.isfinite(result.sigma0) and result.redundancy > 0:
            s0 = float(result.sigma0)
        cb = {} if result is None else result.cofactor_groups
        per["image"] = position_std(cb.get("exterior"), s0, m)
        per["point"] = position_std(cb.get("points"), s0, p)
        both = np.concatenate([per["image"], per["point"]])
        both = both[np.isfinite(both)]
        lo = 0.0
        hi = float(np.percentile(both, 95)) if both.size else 1.0
        hi = hi if hi > 0 else 1.0
    return Quality(key, label, unit, worse_high, per["image"], per["point"], lo, hi)


def colour_bar(quality: Quality, width: int = 240, height: int = 14) -> NDArray[np.uint8]:
    """The legend's colour scale as an RGB image (height, width, 3), good at the left."""
    t = np.linspace(0.0, 1.0, width)
    row = ramp(t, 1.0, STOPS)
    img = np.repeat(row[None, :, :], height, axis=0)
    img[:, [0, -1]] = 60  # a thin frame at both ends
    img[[0, -1], :] = 60
    return img


def legend_text(quality: Quality) -> str:
    """Markdown under the colour bar: the measure and the values at its ends and middle."""
    unit = f" {quality.unit}" if quality.unit else ""
    head = f"**{quality.label}**" + (f" [{quality.unit}]" if quality.unit else "")
    fmt = "{:.3g}"
    t = quality.ticks(3)
    n_img = int(np.isfinite(quality.image).sum())
    n_pt = int(np.isfinite(quality.point).sum())
    return (
        f"{head}  \n"
        f"good {fmt.format(t[0])} · {fmt.format(t[1])} · {fmt.format(t[2])} bad{unit}  \n"
        f"grey: not available ({quality.image.size - n_img} images, "
        f"{quality.point.size - n_pt} points)"
    )
