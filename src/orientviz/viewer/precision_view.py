"""Precision as the viewer draws it: confidence ellipsoids and correlations, as plain arrays.

No viser here. The covariances are the bundle's own selected cofactor blocks
(:mod:`orientviz.bundle.precision._precision`: per point 3 × 3, per image 6 × 6, and the 6 × 6
blocks of the image pairs that share a point, ``exterior_pairs``), scaled by σ̂0². The
bundle computes them once per adjustment at the cost of about one factorisation; what
the viewer adds per redraw — eigen-decompositions and meshes — is done only for what is
shown (the selected image's points, or at most :data:`ELLIPSOID_LIMIT` points; the
selected image's station and those of its neighbours).

Confidence: the ellipsoid {x : xᵀ C⁻¹ x = k²} with k² the χ² quantile of 3 degrees of
freedom holds the true point with the chosen probability (k = 1 holds it only with
19.9 %; 95 % needs k = 2.80).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .edits import diagonal_blocks
from .shapes import ramp

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: At most this many point ellipsoids are drawn (the largest ones).
ELLIPSOID_LIMIT: int = 3000
#: At most this many neighbours in the correlation strip (the most correlated).
STRIP_NEIGHBOURS: int = 12
PARAMS: tuple[str, ...] = ("X0", "Y0", "Z0", "ω", "φ", "κ")


def confidence_factor(level: float, dof: int = 3) -> float:
    """k = √χ²(level; dof): the scale of the ellipsoid holding a point with ``level``."""
    if not 0.0 < level < 1.0:
        raise ValueError(f"a confidence level lies between 0 and 1, got {level}")
    from scipy.special import chdtri  # scipy.special loads many modules: only once a precision is drawn

    return float(np.sqrt(chdtri(dof, 1.0 - level)))  # χ²_dof quantile at ``level``


def has_covariances(result) -> bool:
    """True if ``result`` carries cofactors that ellipsoids are drawn from (its precision):
    the dense cofactor or the stored point or exterior blocks."""
    if result is None:
        return False
    groups = getattr(result, "cofactor_groups", None) or {}
    return (
        getattr(result, "cofactor", None) is not None or "points" in groups or "exterior" in groups
    )


def _s0(result) -> float:
    ok = result is not None and np.isfinite(result.sigma0) and result.redundancy > 0
    return float(result.sigma0) if ok else 1.0


def point_covariances(result, points: I64) -> tuple[I64, F64]:
    """Covariances (k, 3, 3) in m² of ``points`` that have one (not fixed, not left out)."""
    Q = None if result is None else diagonal_blocks(result, "points", 3)
    idx = np.asarray(points, dtype=np.int64).reshape(-1)
    if Q is None or np.ndim(Q) != 3 or idx.size == 0:
        return np.zeros(0, np.int64), np.zeros((0, 3, 3))
    Qs = np.asarray(Q)[idx]
    tr = np.einsum("nii->n", Qs)
    ok = np.isfinite(tr) & (tr > 0)
    return idx[ok], _s0(result) ** 2 * Qs[ok]


def station_covariances(result, images: I64) -> tuple[I64, F64]:
    """Covariances (k, 3, 3) in m² of the projection centres of ``images``."""
    Q = None if result is None else diagonal_blocks(result, "exterior", 6)
    idx = np.asarray(images, dtype=np.int64).reshape(-1)
    if Q is None or np.ndim(Q) != 3 or idx.size == 0:
        return np.zeros(0, np.int64), np.zeros((0, 3, 3))
    Qs = np.asarray(Q)[idx][:, :3, :3]
    tr = np.einsum("nii->n", Qs)
    ok = np.isfinite(tr) & (tr > 0)
    return idx[ok], _s0(result) ** 2 * Qs[ok]


def largest_first(idx: I64, cov: F64, limit: int = ELLIPSOID_LIMIT) -> tuple[I64, F64]:
    """Keep the ``limit`` covariances with the largest trace."""
    if idx.size <= limit:
        return idx, cov
    keep = np.argsort(-np.einsum("nii->n", cov), kind="stable")[:limit]
    return idx[keep], cov[keep]


def neighbour_correlations(result, image: int, m: int) -> tuple[I64, F64]:
    """Correlations of image ``image``'s orientation with its neighbours' (share a point).

    Returns
    -------
    neighbours : ndarray of int, shape (k,)
        The neighbours, most correlated (largest abs(ρ)) first.
    rho : ndarray, shape (k, 6, 6)
        ρ[a, b] between parameter a (X0 … κ) of ``image`` and b of the neighbour.
    """
    pairs = None if result is None else getattr(result, "exterior_pairs", None)
    Qd = None if result is None else diagonal_blocks(result, "exterior", 6)
    if pairs is None or Qd is None:
        return np.zeros(0, np.int64), np.zeros((0, 6, 6))
    keys = np.asarray(pairs.keys)
    i, k = np.divmod(keys, m)
    sel = ((i == image) | (k == image)) & (i != k)
    other = np.where(i[sel] == image, k[sel], i[sel])
    B = np.asarray(pairs.blocks)[sel]
    B = np.where((i[sel] == image)[:, None, None], B, B.transpose(0, 2, 1))  # Q(image, other)
    d = np.sqrt(np.clip(np.einsum("nii->ni", np.asarray(Qd)), 1e-300, None))
    rho = B / (d[image][None, :, None] * d[other][:, None, :])
    order = np.argsort(-np.nanmax(np.abs(rho), axis=(1, 2)), kind="stable")
    return other[order], rho[order]


def heat_strip(rho: F64, cell: int = 7, gap: int = 3) -> NDArray[np.uint8]:
    """The correlation blocks side by side as an RGB image: white (0) … dark red (1).

    One tile of 6 × 6 cells per neighbour (rows: the selected image's X0 … κ, columns:
    the neighbour's), framed in grey and separated by ``gap`` white pixels; abs(ρ) is
    drawn.
    """
    k = rho.shape[0]
    stops = np.array([[255, 255, 255], [250, 200, 120], [220, 60, 40], [110, 0, 20]], float)
    h = 6 * cell
    w = max(k * (6 * cell + gap) - gap, 1)
    img = np.full((h, w, 3), 255, np.uint8)
    for t in range(k):
        tile = ramp(np.abs(rho[t]).reshape(-1), 1.0, stops).reshape(6, 6, 3)
        tile = np.repeat(np.repeat(tile, cell, axis=0), cell, axis=1)
        tile[[0, -1], :] = 150  # a thin grey frame: tiles stay apart where ρ ≈ 0
        tile[:, [0, -1]] = 150
        x = t * (6 * cell + gap)
        img[:, x : x + 6 * cell] = tile
    return img


def auto_gain(cov: F64, k: float, spacing: float) -> float:
    """Exaggeration (1, 2 or 5 × 10ⁿ) drawing the median largest semi-axis k·σ as 0.3 spacing."""
    if cov.shape[0] == 0:
        return 1.0
    big = k * np.sqrt(np.clip(np.linalg.eigvalsh(cov)[:, -1], 0.0, None))
    med = float(np.median(big))
    if med <= 0:
        return 1.0
    g = 0.3 * spacing / med
    e = np.floor(np.log10(g))
    m = g / 10**e
    return float((5 if m >= 5 else 2 if m >= 2 else 1) * 10**e)
