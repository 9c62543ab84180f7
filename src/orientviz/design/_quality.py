"""The quality of a design: precision, reliability and weak spots named in words.

:class:`DesignQuality` collects what a planner looks at, from the bundle's own precision
(:func:`orientviz.bundle.bundle_adjust` with ``precision=True``: per-point 3×3 and
per-image 6×6 cofactor blocks, redundancy numbers, the gains of each ray) and the
reliability per ray (:func:`orientviz.bundle.ray_reliability`). With error-free
observations and the a-priori weights (σ0 = 1) the cofactors are the covariances of the
design, in m² and rad².
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np
import scipy.stats
from numpy.typing import NDArray

from ..block import CONTROL, Block

F64 = NDArray[np.float64]

#: A point is named weak when its σ is at least this multiple of the block's median.
WEAK_RATIO: float = 1.5


@dataclass
class DesignQuality:
    """Predicted precision and reliability of a block design.

    Attributes
    ----------
    point_sigma : ndarray, shape (p, 3)
        σ_X, σ_Y, σ_Z of every point, m.
    point_cov : ndarray, shape (p, 3, 3)
        Covariance of every point, m².
    station_sigma : ndarray, shape (m, 6)
        σ of X0, Y0, Z0 (m) and ω, φ, κ (rad) of every image.
    ellipsoid_axes : ndarray, shape (p, 3)
        Semi-axes (m, ascending) of every point's confidence ellipsoid at ``level``
        (computed from ``point_cov`` when first asked for).
    ellipsoid_dirs : ndarray, shape (p, 3, 3)
        Their directions (columns, unit vectors in the object frame).
    level : float
        Probability of the confidence ellipsoids.
    redundancy : ndarray, shape (n, 2)
        Redundancy numbers r_x, r_y of each image coordinate (block.observations order).
    mdb : ndarray, shape (n,)
        Minimal detectable bias of each ray along its weakest direction, mm (inf: not
        testable).
    external : ndarray, shape (n,)
        Baarda's δ̄0 of each ray: the largest effect of an undetected blunder on any
        function of the unknowns, in units of its σ (dimensionless; inf: not testable).
    point_shift : ndarray, shape (n,)
        Largest shift (m) of the ray's point caused by an undetected blunder of the ray.
    control : ndarray of bool, shape (p,)
        Control points (some coordinate given).
    weak_spots : list of str
        The weak spots of the design in words.
    summary : dict
        Block figures (m): median / RMS / max σ_XY and σ_Z of the non-control points,
        max σ of the projection centres, mean redundancy number, largest finite MDB (mm)
        and δ̄0, the number of rays that cannot be tested.
    """

    point_sigma: F64
    point_cov: F64
    station_sigma: F64
    level: float
    redundancy: F64
    mdb: F64
    external: F64
    point_shift: F64
    control: NDArray[np.bool_]
    weak_spots: list[str] = field(default_factory=list)
    summary: dict = field(default_factory=dict)

    @functools.cached_property
    def _ellipsoids(self) -> tuple[F64, F64]:
        return ellipsoids(self.point_cov, self.level)

    @property
    def ellipsoid_axes(self) -> F64:
        """Semi-axes (m, ascending) of the confidence ellipsoids, (p, 3)."""
        return self._ellipsoids[0]

    @property
    def ellipsoid_dirs(self) -> F64:
        """Directions of the semi-axes (columns, unit vectors), (p, 3, 3)."""
        return self._ellipsoids[1]

    @property
    def sigma_xy(self) -> F64:
        """σ_XY = √((σ_X² + σ_Y²)/2) of every point, m."""
        return np.sqrt(0.5 * (self.point_sigma[:, 0] ** 2 + self.point_sigma[:, 1] ** 2))

    def per_point(self, values: F64, block: Block) -> F64:
        """The largest value of a per-ray quantity (n,) over each point's rays (p,);
        NaN for points without rays."""
        v = np.asarray(values, float)
        out = np.full(block.n_points, -np.inf)
        np.maximum.at(out, block.observations.point, np.where(np.isnan(v), -np.inf, v))
        return np.where(np.isneginf(out), np.nan, out)


def ellipsoids(cov: F64, level: float = 0.95) -> tuple[F64, F64]:
    """Semi-axes (ascending, m) and directions of 3-D confidence ellipsoids.

    Parameters
    ----------
    cov : ndarray, shape (p, 3, 3)
        Covariances, m².
    level : float
        Probability inside the ellipsoid (χ² with 3 degrees of freedom).
    """
    k = scipy.stats.chi2.ppf(level, 3)
    good = np.isfinite(cov).all(axis=(1, 2))
    lam = np.full((cov.shape[0], 3), np.nan)
    vec = np.full((cov.shape[0], 3, 3), np.nan)
    if good.any():
        w, v = np.linalg.eigh(cov[good])
        lam[good], vec[good] = np.clip(w, 0.0, None), v
    return np.sqrt(k * lam), vec


def _nearest(xy: F64, ref: F64) -> F64:
    """Distance (m) of each position to the nearest reference position (inf if none)."""
    if ref.shape[0] == 0:
        return np.full(xy.shape[0], np.inf)
    d = np.linalg.norm(xy[:, None, :] - ref[None, :, :], axis=2)
    return d.min(axis=1)


def weak_spots(q: DesignQuality, block: Block, base_m: float) -> list[str]:
    """The design's weak spots in words.

    Parameters
    ----------
    q : DesignQuality
    block : Block
        The design block (true positions).
    base_m : float
        The air base B in m (distances are said in base lengths).
    """
    out = []
    P = block.points
    tie = ~q.control
    xy = P.xyz[:, :2]
    names = P.ids
    for label, sig, given in (
        ("σ_Z", q.point_sigma[:, 2], np.isfinite(P.xyz_known[:, 2]) & q.control),
        ("σ_XY", q.sigma_xy, np.isfinite(P.xyz_known[:, 0]) & q.control),
    ):
        s = sig[tie]
        if s.size == 0 or not np.isfinite(s).any():
            continue
        med = float(np.nanmedian(s))
        ratio = sig / med
        bad = np.flatnonzero(tie & (ratio >= WEAK_RATIO))
        if bad.size == 0:
            continue
        worst = bad[np.nanargmax(ratio[bad])]
        dist = _nearest(xy[[worst]], xy[given])[0] / base_m
        kind = "height" if label == "σ_Z" else "planimetric"
        where = (
            f"{dist:.1f} base lengths from the nearest {kind} control"
            if np.isfinite(dist)
            else f"in a block without {kind} control"
        )
        out.append(
            f"{bad.size} points with {label} ≥ {WEAK_RATIO:g}× the block's median "
            f"({med * 1e3:.1f} mm); the worst, point {names[worst]}, lies {where}: "
            f"{label} {ratio[worst]:.1f}× the median ({sig[worst] * 1e3:.1f} mm)"
        )
    nt = ~np.isfinite(q.mdb) & np.isfinite(q.redundancy).all(1)
    if nt.any():
        pts = np.unique(block.observations.point[nt])
        out.append(
            f"{int(nt.sum())} image points of {pts.size} object points cannot be tested: a "
            "blunder along the weakest direction is absorbed (redundancy number ≈ 0, e.g. "
            "a point seen in two images only, whose error along the base moves the point)"
        )
    ext = q.external[np.isfinite(q.external)]
    if ext.size:
        lim = 10.0
        big = int((ext > lim).sum())
        if big:
            out.append(
                f"{big} image points whose largest undetectable blunder moves some "
                f"estimate by more than {lim:g} σ (δ̄0 up to {ext.max():.1f})"
            )
    zs = q.station_sigma[:, 2]
    if np.isfinite(zs).any():
        med = float(np.nanmedian(zs))
        worst = int(np.nanargmax(zs))
        if zs[worst] >= WEAK_RATIO * med:
            out.append(
                f"image {block.images.ids[worst]}: σ_Z0 {zs[worst] / med:.1f}× the median "
                f"of the projection centres ({zs[worst] * 1e3:.1f} mm)"
            )
    return out


def summarise(q: DesignQuality) -> dict:
    """Block figures of a quality (m, mm for the MDB; see :class:`DesignQuality`)."""
    tie = ~q.control
    sxy, sz = q.sigma_xy[tie], q.point_sigma[tie, 2]
    fin = np.isfinite(q.mdb)
    ext = q.external[np.isfinite(q.external)]
    return {
        "sigma_xy_median": float(np.nanmedian(sxy)),
        "sigma_xy_rms": float(np.sqrt(np.nanmean(sxy**2))),
        "sigma_xy_max": float(np.nanmax(sxy)),
        "sigma_z_median": float(np.nanmedian(sz)),
        "sigma_z_rms": float(np.sqrt(np.nanmean(sz**2))),
        "sigma_z_max": float(np.nanmax(sz)),
        "station_sigma_max": float(np.nanmax(q.station_sigma[:, :3])),
        "redundancy_mean": float(np.nanmean(q.redundancy)),
        "mdb_max_mm": float(q.mdb[fin].max()) if fin.any() else float("inf"),
        "external_max": float(ext.max()) if ext.size else float("inf"),
        "untestable_rays": int((~fin & np.isfinite(q.redundancy).all(1)).sum()),
        "n_control": int(q.control.sum()),
    }


def quality_from_arrays(
    block: Block,
    point_cov: F64,
    exterior_cov: F64,
    redundancy: F64,
    rel,
    base_m: float,
    level: float = 0.95,
) -> DesignQuality:
    """Assemble a :class:`DesignQuality` from covariances and a ray reliability.

    Parameters
    ----------
    block : Block
    point_cov : ndarray, shape (p, 3, 3)
        m².
    exterior_cov : ndarray, shape (m, 6, 6)
        Diagonal blocks of the orientations' covariance (m², rad²).
    redundancy : ndarray, shape (n, 2)
        Redundancy numbers of the image coordinates.
    rel : RayReliability
        From :func:`orientviz.bundle.ray_reliability` (MDB in mm, δ̄0, point shifts).
    base_m : float
        Air base, m.
    level : float
        Probability of the confidence ellipsoids.
    """
    sig = np.sqrt(np.clip(np.einsum("nii->ni", point_cov), 0.0, None))
    ssig = np.sqrt(np.clip(np.einsum("nii->ni", exterior_cov), 0.0, None))
    ctrl = block.points.role == CONTROL
    q = DesignQuality(
        point_sigma=sig, point_cov=point_cov, station_sigma=ssig, level=level, redundancy=redundancy, mdb=rel.mdb_weak,
        external=rel.external, point_shift=rel.point_shift_max, control=ctrl,
    )  # fmt: skip
    q.weak_spots = weak_spots(q, block, base_m)
    q.summary = summarise(q)
    return q
