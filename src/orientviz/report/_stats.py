"""Numbers behind the report's tests and warnings: χ² test of σ0, intersection angles,
image coverage, which observations were adjusted, correlation matrices.

All functions work on plain arrays and :class:`~orientviz.block.Block` tables; none
imports matplotlib.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..adjust.result import Adjustment
from ..block import Block
from ..io.problem import Problem
from ..io.solution import Solution

F64 = NDArray[np.float64]


# --------------------------------------------------------------------------- helpers
def used_observations(adj: Adjustment) -> NDArray[np.bool_]:
    """Observations that took part in the adjustment (finite redundancy number)."""
    if adj.redundancy_numbers is None:
        return np.ones(adj.n_observations, bool)
    return np.isfinite(adj.redundancy_numbers)


def image_slice(adj: Adjustment, solution: Solution) -> slice:
    """The range of image-coordinate observations in the observation vector."""
    sl = adj.obs_slices.get("image")
    if sl is not None:
        return sl
    return slice(0, adj.n_observations) if solution.observation_quantity == "image" else slice(0, 0)


def split_label(label: str) -> tuple[str, str, str]:
    """(image, point, component) from labels such as ``img/pt/x``, ``pt/x`` or ``name``."""
    parts = label.split("/")
    if len(parts) >= 3:
        return parts[0], "/".join(parts[1:-1]), parts[-1]
    if len(parts) == 2:
        return "", parts[0], parts[1]
    return "", "", label


def chi2_test(sigma0: float, r: int, alpha: float = 0.05) -> dict[str, Any]:
    """Global test of σ̂0 against the a-priori σ0 = 1: T = r σ̂0² ~ χ²(r), two-sided.

    Returns a dict with ``T``, ``lower``/``upper`` (quantiles of χ²(r) at α/2 and
    1 − α/2), the corresponding bounds for σ̂0, ``alpha`` and ``accepted`` (None when
    r = 0 or σ̂0 is not finite).
    """
    from scipy.special import gammaincinv  # scipy.stats would take a second to import

    out: dict[str, Any] = {
        "alpha": alpha,
        "r": int(r),
        "T": float("nan"),
        "lower": float("nan"),
        "upper": float("nan"),
        "sigma0_lower": float("nan"),
        "sigma0_upper": float("nan"),
        "accepted": None,
    }
    if r <= 0 or not np.isfinite(sigma0):
        return out
    # quantile of χ²(r): P(r/2, x/2) = q  ⇔  x = 2 · P⁻¹(r/2, q)
    lo, hi = 2.0 * gammaincinv(r / 2, alpha / 2), 2.0 * gammaincinv(r / 2, 1 - alpha / 2)
    T = r * sigma0**2
    out.update(
        T=float(T),
        lower=float(lo),
        upper=float(hi),
        sigma0_lower=math.sqrt(lo / r),
        sigma0_upper=math.sqrt(hi / r),
        accepted=bool(lo <= T <= hi),
    )
    return out


def intersection_angles(block: Block, X0: F64, xyz: F64) -> F64:
    """Largest angle (rad) between two rays of each point; NaN for points with < 2 rays.

    Parameters
    ----------
    block : Block
        For the observations (which image sees which point).
    X0 : ndarray, shape (m, 3)
        Projection centres, m.
    xyz : ndarray, shape (p, 3)
        Point coordinates, m.
    """
    obs = block.observations
    out = np.full(block.n_points, np.nan)
    if len(obs) == 0:
        return out
    order = np.argsort(obs.point, kind="stable")
    pt = obs.point[order]
    d = xyz[pt] - X0[obs.image[order]]
    with np.errstate(invalid="ignore", divide="ignore"):
        d = d / np.linalg.norm(d, axis=1, keepdims=True)
    counts = np.bincount(pt, minlength=block.n_points)
    kmax = int(counts.max(initial=0))
    best = np.full(block.n_points, -np.inf)
    for off in range(1, kmax):
        same = np.flatnonzero(pt[:-off] == pt[off:])
        if not same.size:
            break
        cosang = np.clip(np.einsum("ij,ij->i", d[same], d[same + off]), -1.0, 1.0)
        ang = np.arccos(cosang)
        # the pairs of one point are adjacent (pt is sorted): the largest of each run
        p = pt[same]
        run = np.flatnonzero(np.r_[True, p[1:] != p[:-1]])
        first = p[run]
        best[first] = np.maximum(best[first], np.maximum.reduceat(ang, run))
    ok = np.isfinite(best)
    out[ok] = best[ok]
    return out


def image_coverage(block: Block, only: NDArray[np.bool_] | None = None) -> F64:
    """Area of the convex hull of each image's measured points over the format area (0…1).

    ``only``: compute it for these images (boolean mask over the images); the others
    are NaN.
    """
    cov = np.zeros(block.n_images)
    todo = range(block.n_images) if only is None else np.flatnonzero(only).tolist()
    if only is not None:
        cov[~np.asarray(only, bool)] = np.nan
    if not todo:
        return cov
    from scipy.spatial import ConvexHull, QhullError  # only where a hull is computed

    obs = block.observations
    fmt_area = np.prod(block.cameras.format_mm[block.images.camera], axis=1)
    order = np.argsort(obs.image, kind="stable")
    starts = np.searchsorted(obs.image[order], np.arange(block.n_images + 1))
    for i in todo:
        xy = obs.xy[order[starts[i] : starts[i + 1]]]
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        if xy.shape[0] < 3 or not fmt_area[i] > 0:
            continue
        try:
            cov[i] = ConvexHull(xy).volume / fmt_area[i]
        except (QhullError, ValueError):
            cov[i] = 0.0
    return cov


def block_of(problem: Problem) -> Block | None:
    """The problem's :class:`~orientviz.block.Block`, or None for kinds without one."""
    return problem.data if isinstance(problem.data, Block) else None


def condition_number(C: F64) -> float:
    """Condition number of a correlation matrix (inf if singular)."""
    ev = np.linalg.eigvalsh(C)
    if not np.all(np.isfinite(ev)):
        return float("inf")
    return float(ev[-1] / ev[0]) if ev[0] > 0 else float("inf")


def conditioned_below(C: F64, limit: float) -> NDArray[np.bool_]:
    """Which 3 × 3 correlation matrices of the stack ``C`` (k, 3, 3) certainly have a
    condition number below ``limit``, without their eigenvalues.

    ``C`` has a unit diagonal. It is positive definite when its leading minors
    1 − ρ₀₁² and det C are (Sylvester); then its largest eigenvalue is at most
    h = maxᵢ (1 + Σⱼ≠ᵢ ``|ρᵢⱼ|``) (Gershgorin), its middle one too, so the smallest is at
    least det C / h² and the condition number at most h³ / det C. A matrix is certified
    when h³ / det C lies below ``limit`` by a relative 1e-6: the minors, formed from
    entries of size ≤ 1, and the eigenvalues of a symmetric solver are both within a few
    10⁻¹⁶ of exact, far inside that margin for det C ≥ 10⁻⁸ · h³ ≥ 10⁻⁸ (``limit`` =
    10⁸), so ``eigvalsh`` would find these condition numbers below ``limit`` as well.
    False for the others (near-singular, indefinite, NaN): those need their eigenvalues.
    """
    a, b, c = C[:, 0, 1], C[:, 0, 2], C[:, 1, 2]
    with np.errstate(invalid="ignore"):
        minor = 1.0 - a * a
        det = 1.0 + 2.0 * a * b * c - a * a - b * b - c * c
        h = 1.0 + np.max(np.abs(C).sum(axis=2) - np.abs(np.diagonal(C, axis1=1, axis2=2)), axis=1)
        return (minor > 1e-12) & (det * limit >= h**3 * (1.0 + 1e-6))


def correlation_matrix(Q: F64) -> F64:
    """ρ_ij = Q_ij / sqrt(Q_ii Q_jj) of a cofactor matrix."""
    d = np.sqrt(np.clip(np.diag(Q), 1e-300, None))
    return Q / np.outer(d, d)
