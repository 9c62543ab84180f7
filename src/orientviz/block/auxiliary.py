"""Auxiliary data in the bundle: statoscope, APR profiles, GNSS projection centres.

Ackermann (1974, §19): for small-scale mapping, statoscope and APR data (radar height
profile measurements) in the block adjustment cut the dependence on height control
drastically; today GNSS positions of the projection centres do the same. Three kinds:

* **GNSS** — observed projection centres X0, Y0, Z0 (m) with σ, affected per strip by
  an offset (and optionally a linear drift with time);
* **statoscope** — observed flying heights Z0 relative to an isobaric surface: good
  differences within a strip, an unknown offset (and drift) per strip;
* **APR** — terrain heights along the flight line (airborne profile recorder: radar
  clearance below the aircraft plus statoscope height): Z of ground points at the nadir
  of each image, again with an unknown offset per strip.

They enter :func:`orientviz.block.bundle.bundle_adjust` as weighted observations through
the block's existing tables: ``images.X0_obs``/``X0_sigma`` (GNSS, statoscope: only Z
given) and height-only weighted control points (APR: ``points.xyz_known[:, 2]`` and
``points.sigma[:, 2]``, X and Y not given).

Offsets and drifts per strip are unknowns of a *joint* adjustment: pass the data as
``auxiliary=[...]`` to :func:`orientviz.block.bundle.bundle_adjust` or
:func:`orientviz.block.models.independent_models` (rows, weights and the offset/drift
unknowns: :mod:`orientviz.block.auxiliary_obs`). That is the way to adjust.

:func:`adjust_with_auxiliary` is kept **for teaching**: it estimates the offsets by
**alternation** — adjust with the data corrected by the current offsets, fit offset
(+ drift) per strip to the differences between the adjusted and the observed values,
correct, repeat until the corrections fall below ``tol`` σ (a fixed-point iteration,
accelerated by Anderson mixing). Its fixed point is the joint least-squares solution
(``tests/block/test_auxiliary_obs.py`` compares them); it shows how slowly plain
alternation converges when offsets and block heights are strongly correlated, and it
gives no precision of the offsets.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..adjust.result import Adjustment
from ..errors import InputError
from ..model import CONTROL, TIE, Block
from .bundle import bundle_adjust

F64 = NDArray[np.float64]
KINDS = ("gnss", "statoscope", "apr")

__all__ = [
    "Auxiliary",
    "AuxiliaryResult",
    "adjust_with_auxiliary",
    "check_differences",
    "check_errors",
    "height_control_at_ends",
    "simulate_auxiliary",
]


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


def _strip_time(block: Block) -> F64:
    t = np.zeros(block.n_images)
    for s in np.unique(block.images.strip):
        ix = np.flatnonzero(block.images.strip == s)
        t[ix] = np.linspace(0.0, 1.0, ix.size) if ix.size > 1 else 0.0
    return t


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
        From :func:`orientviz.block.simulate.simulate_block`.
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
    t_img = _strip_time(tb)
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


@dataclass
class AuxiliaryResult:
    """Result of :func:`adjust_with_auxiliary`.

    Attributes
    ----------
    adjustment : Adjustment
        The last bundle adjustment.
    offsets : dict of str to ndarray
        Per kind: estimated offset (and drift) per strip, shape (strips, 3 or 1, 1 or 2), m.
    rounds : int
        Alternation rounds (bundle adjustments) used.
    converged : bool
        Whether the offsets settled below ``tol`` σ.
    history : list of float
        Largest offset change (in σ) per round.
    """

    adjustment: Adjustment
    offsets: dict = field(default_factory=dict)
    rounds: int = 0
    converged: bool = False
    history: list = field(default_factory=list)


def _apply(block: Block, aux: list[Auxiliary], corr: dict) -> Block:
    b = block.copy()
    for a in aux:
        c = corr[a.kind]
        if a.kind == "gnss":
            b.images.X0_obs[a.index] = a.values - c
            b.images.X0_sigma[a.index] = a.sigma
        elif a.kind == "statoscope":
            # X, Y carry the approximate position with σ = NaN (not observed): the bundle's
            # datum check needs finite planimetric positions of height observations
            b.images.X0_obs[a.index, :2] = b.images.X0[a.index, :2]
            b.images.X0_sigma[a.index, :2] = np.nan
            b.images.X0_obs[a.index, 2] = a.values - c
            b.images.X0_sigma[a.index, 2] = a.sigma
        else:
            P = b.points
            ok = P.role[a.index] != CONTROL
            ix = a.index[ok]
            P.role[ix] = CONTROL
            # X, Y: the approximate position with σ = NaN (not given as observations);
            # finite values keep the bundle's datum check away from NaN
            P.xyz_known[ix, :2] = P.xyz[ix, :2]
            P.xyz_known[ix, 2] = (a.values - c)[ok]
            P.sigma[ix] = np.nan
            P.sigma[ix, 2] = a.sigma
    return b


def _fit(a: Auxiliary, diff: F64) -> tuple[F64, F64]:
    """Offset (+ drift) per strip fitted to diff = observed − adjusted; returns (params, per-obs)."""
    d = diff.reshape(diff.shape[0], -1)
    ns = int(a.strip.max()) + 1
    npar = 2 if a.drift else 1
    par = np.zeros((ns, d.shape[1], npar))
    per = np.zeros_like(d)
    for s in range(ns):
        sel = a.strip == s
        if not sel.any():
            continue
        A = np.ones((int(sel.sum()), npar))
        if a.drift:
            A[:, 1] = a.time[sel]
        coef = np.linalg.lstsq(A, d[sel], rcond=None)[0]  # (npar, dims)
        par[s] = coef.T
        per[sel] = A @ coef
    return par, per.reshape(diff.shape)


def adjust_with_auxiliary(
    block: Block,
    aux: list[Auxiliary],
    *,
    max_rounds: int = 30,
    tol: float = 0.05,
    **bundle_options,
) -> AuxiliaryResult:
    """Bundle adjustment with auxiliary observations, offsets/drifts by alternation.

    For teaching (see the module docstring); the joint adjustment is
    ``bundle_adjust(block, auxiliary=aux)``.

    Parameters
    ----------
    block : Block
        Approximate values and image observations (its own control as given).
    aux : list of Auxiliary
        At most one entry per kind.
    max_rounds : int
        Limit of alternation rounds.
    tol : float
        Stop when no offset changes by more than ``tol`` · σ of its data.
    **bundle_options
        Passed to :func:`bundle_adjust` (``control="weighted"`` is implied: APR heights
        are weighted observations; fixed control stays fixed).

    Returns
    -------
    AuxiliaryResult
    """
    kinds = [a.kind for a in aux]
    if len(set(kinds)) != len(kinds) or any(k not in KINDS for k in kinds):
        raise InputError(f"aux: expected at most one each of {', '.join(KINDS)}, got {kinds}")
    if "gnss" in kinds and "statoscope" in kinds:
        raise InputError("aux: gnss and statoscope both observe Z0; give one of them")
    est = [a for a in aux if a.offsets]
    shapes = [_fit(a, np.zeros_like(a.values))[0].shape for a in est]
    sizes = [int(np.prod(sh)) for sh in shapes]

    def unpack(x):
        out, pos = {}, 0
        for a, sh, n in zip(est, shapes, sizes):
            out[a.kind] = x[pos : pos + n].reshape(sh)
            pos += n
        return out

    def corrections(x):
        corr = {a.kind: np.zeros_like(a.values) for a in aux}
        for a, par in zip(est, unpack(x).values()):
            per = par[a.strip, :, 0] + (par[a.strip, :, 1] * a.time[:, None] if a.drift else 0.0)
            corr[a.kind] = per.reshape(a.values.shape)
        return corr

    x = np.zeros(sum(sizes))
    xs: list = []
    gs: list = []
    history: list[float] = []
    opts = dict(bundle_options)
    opts["control"] = "weighted"
    adj = None
    converged = not est
    rounds = 0
    for rounds in range(1, max_rounds + 1):  # noqa: B007
        corr = corrections(x)
        adj = bundle_adjust(_apply(block, aux, corr), **opts)
        if converged:
            break
        ext, pts = adj.extra["exterior"], adj.extra["points"]
        g = []
        for a in est:
            if a.kind == "gnss":
                adjusted = ext[a.index, :3]
            elif a.kind == "statoscope":
                adjusted = ext[a.index, 2]
            else:
                adjusted = pts[a.index, 2]
            g.append(_fit(a, a.values - adjusted)[0].ravel())
        g = np.concatenate(g)
        cg = corrections(g)
        change = max(float(np.max(np.abs(cg[a.kind] - corr[a.kind]))) / a.sigma for a in est)
        history.append(change)
        if change < tol:
            converged, x = True, g
            adj = bundle_adjust(_apply(block, aux, cg), **opts)
            break
        # Anderson acceleration (depth 3) of the fixed-point iteration x -> g(x)
        xs.append(x)
        gs.append(g)
        xs, gs = xs[-4:], gs[-4:]
        if len(xs) >= 2:
            F = np.stack([gi - xi for gi, xi in zip(gs, xs)], axis=1)
            dF, dG = np.diff(F, axis=1), np.diff(np.stack(gs, axis=1), axis=1)
            gamma = np.linalg.lstsq(dF, F[:, -1], rcond=None)[0]
            x = g - dG @ gamma
        else:
            x = g
    params = unpack(x)
    return AuxiliaryResult(adj, params, rounds, converged, history)


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
        The simulated block (:func:`orientviz.block.simulate.simulate_block`): its
        ``block`` names the check points (role 2), its ``truth`` holds their true
        coordinates.
    result : ndarray, shape (p, 3), or Adjustment
        Adjusted coordinates of all points of the block in m, or an adjustment of it:
        a bundle result (:func:`orientviz.block.bundle.bundle_adjust`, check points
        intersected from their own rays, ``extra["points"]``) or an independent-model
        result (:func:`orientviz.block.models.independent_models`, ``extra["xyz"]``).

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
        extra = result.extra
        key = "xyz" if "xyz" in extra else "points" if "points" in extra else None
        if key is None:
            raise InputError(
                "check_errors: the adjustment has no adjusted points "
                '(expected extra["xyz"] or extra["points"])'
            )
        xyz = np.asarray(extra[key], dtype=float)
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
