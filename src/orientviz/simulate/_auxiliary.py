"""Simulated auxiliary data and check-point errors of simulated blocks.

:func:`simulate_auxiliary` draws GNSS / statoscope / APR observations
(:class:`orientviz.block.Auxiliary`) from the truth of a simulated block, with per-strip
offsets and drifts; :func:`check_differences` and :func:`check_errors` compare adjusted
check points with the truth (m); :func:`height_control_at_ends` thins the control to
full control at the block's ends (Ackermann 1974, §19: with statoscope/APR data a block
needs height control only there).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..adjust.result import Adjustment
from ..block import CONTROL, KINDS, TIE, Auxiliary, Block, BlockAdjustment, strip_time
from ..errors import InputError

F64 = NDArray[np.float64]

__all__ = [
    "check_differences",
    "check_errors",
    "height_control_at_ends",
    "simulate_auxiliary",
]


def simulate_auxiliary(
    sim,
    kind: str,
    *,
    rng: np.random.Generator,
    sigma: float | None = None,
    offset_sigma: float | None = None,
    drift_sigma: float = 0.0,
    estimate_offsets: bool = True,
) -> Auxiliary:
    """Auxiliary observations of a simulated block, from its truth.

    Parameters
    ----------
    sim : SimulatedBlock
        From :func:`orientviz.simulate.simulate_block`.
    kind : {"gnss", "statoscope", "apr"}
    rng : numpy.random.Generator
        Source of noise, offsets and drifts.
    sigma : float, optional
        σ of one observation in m (defaults: gnss 0.1, statoscope 0.5, apr 1.0).
    offset_sigma : float, optional
        σ of the per-strip offsets in m (defaults: gnss 0.3, statoscope 20, apr 20).
    drift_sigma : float
        σ of a per-strip linear drift over the strip, m (0: none; then no drift is
        estimated).
    estimate_offsets : bool
        Whether :func:`adjust_with_auxiliary` estimates offsets (False: absolute data).
    """
    if kind not in KINDS:
        raise InputError(f"unknown auxiliary data {kind!r}; expected one of {', '.join(KINDS)}")
    sig = {"gnss": 0.1, "statoscope": 0.5, "apr": 1.0}[kind] if sigma is None else float(sigma)
    osig = (
        {"gnss": 0.3, "statoscope": 20.0, "apr": 20.0}[kind]
        if offset_sigma is None
        else offset_sigma
    )
    if not sig > 0:
        raise InputError(f"sigma: expected a positive σ in m, got {sigma}")
    tb = sim.truth
    strips = tb.images.strip
    ns = int(strips.max()) + 1
    off = rng.normal(0.0, osig, (ns, 3))
    dri = rng.normal(0.0, drift_sigma, (ns, 3)) if drift_sigma > 0 else np.zeros((ns, 3))
    t_img = strip_time(tb)
    if kind in ("gnss", "statoscope"):
        idx = np.arange(tb.n_images)
        st, t = strips, t_img
        true = tb.images.X0.copy()
        obs = true + off[st] + dri[st] * t[:, None] + rng.normal(0.0, sig, true.shape)
        values = obs if kind == "gnss" else obs[:, 2]
    else:
        # the tie point nearest to each image's nadir, if any (profile along the strip)
        o = tb.observations
        near = np.full(tb.n_images, -1, np.int64)
        d2 = np.sum(o.xy**2, axis=1)
        ok = tb.points.role[o.point] == TIE
        for i in range(tb.n_images):
            sel = np.flatnonzero((o.image == i) & ok)
            if sel.size:
                near[i] = o.point[sel[np.argmin(d2[sel])]]
        img = np.flatnonzero(near >= 0)
        idx, first = np.unique(near[img], return_index=True)
        img = img[first]
        st, t = strips[img], t_img[img]
        values = (
            tb.points.xyz[idx, 2] + off[st, 2] + dri[st, 2] * t + rng.normal(0.0, sig, idx.size)
        )
    truth = {"offset": off if kind == "gnss" else off[:, 2:], "drift": dri}
    return Auxiliary(
        kind, idx, values, sig, st, t, drift=drift_sigma > 0, offsets=estimate_offsets, truth=truth
    )


def height_control_at_ends(block: Block, margin_m: float = 100.0) -> Block:
    """A copy of ``block`` whose height control is kept only at the two block ends.

    Height coordinates of control points farther than ``margin_m`` (m) from the first
    and last control column (in X, along the strips) are removed; points left without
    any given coordinate become tie points. Planimetric control stays.
    """
    b = block.copy()
    P = b.points
    ctrl = np.flatnonzero(P.role == CONTROL)
    hz = ctrl[np.isfinite(P.xyz_known[ctrl, 2])]
    if hz.size == 0:
        return b
    X = P.xyz[hz, 0]  # approximate positions: height-only points have no given X
    drop = hz[(X > X.min() + margin_m) & (X < X.max() - margin_m)]
    P.xyz_known[drop, 2] = np.nan
    P.sigma[drop, 2] = np.nan
    P.role[drop[~np.isfinite(P.xyz_known[drop, 0])]] = TIE
    return b


def check_differences(sim, result: F64 | Adjustment) -> tuple[NDArray[np.int64], F64]:
    """True errors of the check points of a simulated block, point by point.

    Parameters
    ----------
    sim : SimulatedBlock
        The simulated block (:func:`orientviz.simulate.simulate_block`): its
        ``block`` names the check points (role 2), its ``truth`` holds their true
        coordinates.
    result : ndarray, shape (p, 3), or Adjustment
        Adjusted coordinates of all points of the block in m, or an adjustment of it:
        a bundle result (:func:`orientviz.bundle.bundle_adjust`, check points
        intersected from their own rays, ``points``) or an independent-model
        result (:func:`orientviz.stereo_models.independent_models`, ``points``).

    Returns
    -------
    index : ndarray of int, shape (k,)
        Point indices (rows of ``sim.block.points``) of the check points with finite
        coordinates.
    d : ndarray, shape (k, 3)
        Adjusted minus true coordinates (ΔX, ΔY, ΔZ) in m.

    Raises
    ------
    InputError
        If the adjustment carries no point coordinates, their number does not match the
        block, or no check point has finite coordinates.
    """
    if isinstance(result, Adjustment):
        if not isinstance(result, BlockAdjustment) or result.points is None:
            raise InputError(
                "check_errors: the adjustment has no adjusted points "
                "(expected a block adjustment with points)"
            )
        xyz = np.asarray(result.points, dtype=float)
    else:
        xyz = np.asarray(result, dtype=float)
    truth = sim.truth.points.xyz
    if xyz.shape != truth.shape:
        raise InputError(
            f"check_errors: expected coordinates of all {truth.shape[0]} points, shape "
            f"{truth.shape}, got {xyz.shape}"
        )
    chk = np.flatnonzero(sim.block.points.role == 2)
    d = xyz[chk] - truth[chk]
    ok = np.all(np.isfinite(d), axis=1)
    if not ok.any():
        raise InputError("check_errors: the block has no check point with finite coordinates")
    return chk[ok], d[ok]


def check_errors(sim, result: F64 | Adjustment) -> tuple[float, float]:
    """RMS true errors of the check points of a simulated block.

    Parameters
    ----------
    sim : SimulatedBlock
        The simulated block; see :func:`check_differences`.
    result : ndarray, shape (p, 3), or Adjustment
        Adjusted coordinates of all points in m, or a bundle or independent-model
        adjustment of the block; see :func:`check_differences`.

    Returns
    -------
    mu_xy : float
        RMS planimetric error per coordinate, sqrt(mean(ΔX² and ΔY²)), in m.
    mu_z : float
        RMS height error in m.

    Raises
    ------
    InputError
        If the adjustment carries no point coordinates, their number does not match the
        block, or no check point has finite coordinates.
    """
    _, d = check_differences(sim, result)
    return float(np.sqrt(np.mean(d[:, :2] ** 2))), float(np.sqrt(np.mean(d[:, 2] ** 2)))
