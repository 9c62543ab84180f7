"""Reliability of the image points (rays) of a bundle block, in two dimensions.

A gross error of an image point is a 2-vector ∇ (mm). With e = P½ ∇ (the error in units
of the a-priori σ) and R the 2×2 block of P½ Q_vv P½ of the ray (diagonal: the redundancy
numbers r_x, r_y; off-diagonal ``redundancy_xy``), the 2-D test of
:mod:`orientviz.adjust.gross2d` sees the non-centrality λ = eᵀ R e. Over the directions of
the image plane λ is smallest along the eigenvector of the smaller eigenvalue r_min of R
and largest along that of r_max, so the *minimal detectable bias* (Baarda, λ = δ0²) is

    MDB_weak = δ0 σ / √r_min   (weakest direction),   MDB_strong = δ0 σ / √r_max.

A tie point seen in two images has one redundancy (its y-parallax): an error of one of
its rays along the base is absorbed by moving the point, r_min = 0, and no test can find
it (``testable`` False, MDB infinite). A third ray — e.g. Gruber's points in the triple
overlap of a strip — controls that direction too.

External reliability: an undetected bias moves the estimates by Δx̂ = Q Jᵀ P ∇. The
bundle keeps, per ray, the gains K = Q_(·, ray) Jᵀ P½ on the ray's own image orientation
(6×2) and point (3×2) (``BundleResult.ray_gains``, :mod:`orientviz.bundle.precision._precision`), so
Δpoint = K_p e and Δorientation = K_e e. Reported here: the shifts caused by the MDB
along the weakest direction, the largest shift caused by any bias on the MDB ellipse
eᵀ R e = δ0², and Baarda's dimensionless δ̄0 = δ0 √((1 − r_min) / r_min), the largest
effect of such a bias on any function of the unknowns in units of its own σ.

All effects are first order (the cofactors of the normal equations). Adjusting again
with the bias added reproduces them up to second-order terms: for error-free data to
~1e-8 at 1e-4 of the MDB and ~1e-3 at the full MDB (``tests/bundle/test_reliability.py``);
with residuals in the data the curvature of the collinearity equations weighted by the
residuals adds terms of the same order (~1e-3 measured on a small block with GNSS data).

Everything is vectorised over the rays; σ is the a-priori σ of the image coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ...adjust.gross import noncentrality
from ...adjust.gross2d import RANK_TOL
from ...adjust.result import Adjustment
from ...block import Block
from ...errors import InputError

F64 = NDArray[np.float64]

__all__ = ["RayReliability", "ray_reliability"]


@dataclass
class RayReliability:
    """Internal and external reliability of every image point (ray) of a bundle block.

    Arrays have one row per observation of the block (``block.observations`` order);
    rays that took no part in the adjustment (check points, eliminated rays) are NaN
    and have ``used`` False.

    Attributes
    ----------
    image, point : ndarray of int, shape (n,)
        Image and point index of each ray.
    used : ndarray of bool, shape (n,)
        The ray was adjusted (it has redundancy numbers).
    r_min, r_max : ndarray, shape (n,)
        Eigenvalues of the ray's 2×2 redundancy block R (dimensionless, in [0, 1]).
    weak_direction : ndarray, shape (n, 2)
        Unit eigenvector of r_min in σ-normalised image coordinates (x, y); with equal σ
        of x and y it is the weakest direction in the image.
    testable : ndarray of bool, shape (n,)
        r_min ≥ ``rank_tol``: an error in any direction can be found.
    mdb_weak, mdb_strong : ndarray, shape (n,)
        Minimal detectable bias along the weakest / strongest direction (mm); inf where
        that eigenvalue is below ``rank_tol``.
    bias_weak : ndarray, shape (n, 2)
        The MDB-sized bias along the weakest direction, x and y (mm); NaN if not testable.
    external : ndarray, shape (n,)
        δ̄0 = δ0 √((1 − r_min) / r_min): the largest effect of a bias with λ = δ0² on any
        function of the unknowns, in units of that function's σ (dimensionless; inf if
        not testable).
    point_shift : ndarray, shape (n, 3)
        Shift of the ray's point (X, Y, Z in m) caused by ``bias_weak``; 0 for fixed
        points, NaN if not testable.
    exterior_shift : ndarray, shape (n, 6)
        Shift of the ray's image orientation caused by ``bias_weak`` (X0, Y0, Z0 in m,
        ω, φ, κ in rad); NaN if not testable.
    point_shift_max, centre_shift_max : ndarray, shape (n,)
        Largest length (m) of the point's / the projection centre's shift over all biases
        of the ray with non-centrality δ0² (the MDB ellipse); inf if not testable.
    alpha0, beta0, delta0, rank_tol : float
        Test level, power, their non-centrality δ0, and the eigenvalue threshold.
    """

    image: NDArray[np.int64]
    point: NDArray[np.int64]
    used: NDArray[np.bool_]
    r_min: F64
    r_max: F64
    weak_direction: F64
    testable: NDArray[np.bool_]
    mdb_weak: F64
    mdb_strong: F64
    bias_weak: F64
    external: F64
    point_shift: F64
    exterior_shift: F64
    point_shift_max: F64
    centre_shift_max: F64
    alpha0: float
    beta0: float
    delta0: float
    rank_tol: float

    def by_point(self, values: F64, n_points: int, reduce: str = "max") -> F64:
        """Per-point reduction of a per-ray quantity over the point's adjusted rays.

        Parameters
        ----------
        values : ndarray, shape (n,)
            A per-ray quantity, e.g. ``mdb_weak`` (inf values count).
        n_points : int
            Number of points of the block.
        reduce : {"max", "min"}
            Largest or smallest value over the rays.

        Returns
        -------
        ndarray, shape (n_points,)
            NaN for points without adjusted rays.
        """
        if reduce not in ("max", "min"):
            raise InputError(f"unknown reduce {reduce!r}; expected 'max' or 'min'")
        v = np.asarray(values, float)
        out = np.full(n_points, -np.inf if reduce == "max" else np.inf)
        ok = self.used & ~np.isnan(v)
        (np.maximum if reduce == "max" else np.minimum).at(out, self.point[ok], v[ok])
        out[~np.isin(np.arange(n_points), self.point[ok])] = np.nan
        return out


def _sym2_eig(a: F64, b: F64, c: F64) -> tuple[F64, F64, F64]:
    """Eigenvalues (small, large) and the unit eigenvector of the small one of [[a, c], [c, b]]."""
    mean, half = 0.5 * (a + b), np.hypot(0.5 * (a - b), c)
    lo, hi = mean - half, mean + half
    # eigenvector of lo: (c, lo − a) or (lo − b, c); take the longer (better conditioned)
    u1 = np.stack([c, lo - a], 1)
    u2 = np.stack([lo - b, c], 1)
    u = np.where((np.abs(lo - a) >= np.abs(lo - b))[:, None], u1, u2)
    nu = np.linalg.norm(u, axis=1)
    # c = 0 and a = b: every direction is an eigenvector; take x
    u = np.where((nu > 0)[:, None], u / np.where(nu > 0, nu, 1.0)[:, None], [1.0, 0.0])
    return lo, hi, u


def _largest_shift(K: F64, a: F64, b: F64, c: F64, delta0: float) -> F64:
    """max ‖K e‖ over eᵀ R e = δ0² (R = [[a, c], [c, b]] positive definite), per ray.

    With e = δ0 R^(-½) f, ‖f‖ = 1, it is δ0 √(largest eigenvalue of R^(-½) KᵀK R^(-½)),
    which equals δ0 √(largest eigenvalue of R⁻¹ KᵀK).
    """
    G = K.transpose(0, 2, 1) @ K  # (n, 2, 2)
    det = a * b - c * c
    Rinv = np.stack([np.stack([b, -c], -1), np.stack([-c, a], -1)], 1) / det[:, None, None]
    M = Rinv @ G  # similar to the symmetric R^(-½) G R^(-½): real, non-negative eigenvalues
    tr = M[:, 0, 0] + M[:, 1, 1]
    dm = M[:, 0, 0] * M[:, 1, 1] - M[:, 0, 1] * M[:, 1, 0]
    lam = 0.5 * tr + np.sqrt(np.maximum(0.25 * tr * tr - dm, 0.0))
    return delta0 * np.sqrt(np.maximum(lam, 0.0))


def ray_reliability(
    adj: Adjustment,
    block: Block,
    *,
    alpha0: float = 0.001,
    beta0: float = 0.80,
    rank_tol: float = RANK_TOL,
) -> RayReliability:
    """Internal and external reliability of every ray of a bundle adjustment.

    Parameters
    ----------
    adj : Adjustment
        Result of :func:`orientviz.bundle.bundle_adjust` with ``precision=True``
        (needs the redundancy numbers, ``redundancy_xy`` and ``ray_gains``).
    block : Block
        The adjusted block (its observations give image, point and σ of each ray).
    alpha0, beta0 : float
        Level and power of the test (defaults 0.1 %, 80 %: δ0 = 4.13).
    rank_tol : float
        Eigenvalues of the 2×2 redundancy block below this count as 0 (not testable),
        as in the 2-D test of :mod:`orientviz.adjust.gross2d`.

    Returns
    -------
    RayReliability

    Raises
    ------
    InputError
        If the adjustment lacks the precision results or does not belong to ``block``.
    """
    gains = getattr(adj, "ray_gains", None)
    if adj.redundancy_numbers is None or gains is None or adj.redundancy_xy is None:
        raise InputError(
            "ray_reliability needs a bundle_adjust result with precision=True "
            "(redundancy numbers, redundancy_xy and ray_gains)"
        )
    obs = block.observations
    n = block.n_observations
    if gains.points.shape[0] != n:
        raise InputError(
            f"the adjustment has {gains.points.shape[0]} rays, the block {n}: "
            "pass the block that was adjusted"
        )
    rn = np.asarray(adj.redundancy_numbers[: 2 * n], float).reshape(n, 2)
    rxy = np.asarray(adj.redundancy_xy, float)
    used = np.isfinite(rn).all(1) & np.isfinite(rxy)
    a, b, c = np.where(used, rn[:, 0], 0.0), np.where(used, rn[:, 1], 0.0), np.where(used, rxy, 0.0)
    lo, hi, u = _sym2_eig(a, b, c)
    d0 = noncentrality(alpha0, beta0)
    sigma = np.asarray(obs.sigma, float)  # (n, 2) mm
    testable = used & (lo >= rank_tol)
    strong = used & (hi >= rank_tol)
    nan = np.full(n, np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        # the MDB along u: e = δ0 u / √r_min (σ units); its length in mm with σ per axis
        e_weak = d0 * u / np.sqrt(np.where(testable, lo, 1.0))[:, None]
        mdb_weak = np.where(testable, np.linalg.norm(e_weak * sigma, axis=1), np.inf)
        # strongest direction: the eigenvector orthogonal to u
        v = np.stack([-u[:, 1], u[:, 0]], 1)
        mdb_strong = np.where(strong, d0 * np.linalg.norm(v * sigma, axis=1) / np.sqrt(hi), np.inf)
        external = np.where(testable, d0 * np.sqrt((1.0 - lo) / lo), np.inf)
    mdb_weak, mdb_strong, external = (
        np.where(used, x, nan) for x in (mdb_weak, mdb_strong, external)
    )
    e_weak[~testable] = np.nan
    Kp = np.nan_to_num(np.asarray(gains.points, float))
    Ke = np.nan_to_num(np.asarray(gains.exterior, float))
    point_shift = np.einsum("nij,nj->ni", Kp, e_weak)
    exterior_shift = np.einsum("nij,nj->ni", Ke, e_weak)
    pmax, cmax = np.full(n, np.inf), np.full(n, np.inf)
    t = testable
    pmax[t] = _largest_shift(Kp[t], a[t], b[t], c[t], d0)
    cmax[t] = _largest_shift(Ke[t, :3], a[t], b[t], c[t], d0)
    pmax[~used], cmax[~used] = np.nan, np.nan
    return RayReliability(
        image=np.asarray(obs.image, np.int64),
        point=np.asarray(obs.point, np.int64),
        used=used,
        r_min=np.where(used, np.clip(lo, 0.0, 1.0), np.nan),
        r_max=np.where(used, np.clip(hi, 0.0, 1.0), np.nan),
        weak_direction=np.where(used[:, None], u, np.nan),
        testable=testable,
        mdb_weak=mdb_weak,
        mdb_strong=mdb_strong,
        bias_weak=e_weak * sigma,
        external=external,
        point_shift=point_shift,
        exterior_shift=exterior_shift,
        point_shift_max=pmax,
        centre_shift_max=cmax,
        alpha0=float(alpha0),
        beta0=float(beta0),
        delta0=float(d0),
        rank_tol=float(rank_tol),
    )
