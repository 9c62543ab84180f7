"""Auxiliary data by alternation (for teaching): bundle, fit offsets, correct, repeat.

:func:`adjust_with_auxiliary` estimates the per-strip offsets (and drifts) of
auxiliary data (:class:`orientviz.block.Auxiliary`) by **alternation** — adjust with the
data corrected by the current offsets, fit offset (+ drift) per strip to the differences
between the adjusted and the observed values, correct, repeat until the corrections fall
below ``tol`` σ (a fixed-point iteration, accelerated by Anderson mixing). Its fixed
point is the joint least-squares solution of ``bundle_adjust(..., auxiliary=[...])``
(``tests/block/test_auxiliary_obs.py`` compares them); it shows how slowly plain
alternation converges when offsets and block heights are strongly correlated, and it
gives no precision of the offsets. To adjust, use the joint adjustment.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..adjust.result import Adjustment
from ..block import CONTROL, KINDS, Auxiliary, Block
from ..errors import InputError
from .loop._adjust import bundle_adjust

F64 = NDArray[np.float64]

__all__ = ["AuxiliaryResult", "adjust_with_auxiliary"]


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
        ext, pts = adj.exterior, adj.points
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
