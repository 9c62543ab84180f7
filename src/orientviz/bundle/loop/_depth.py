"""The depth of the points a step held (their block V numerically singular), sought alone.

A point whose rays have become nearly parallel — it recedes along them, towards infinity,
or was thrown far off by an earlier step — has a block V whose depth eigenvalue is below
rounding; the step then holds it along that direction
(:func:`~orientviz.bundle.reduced.inv3_held`: V⁺ for V⁻¹) and solves only its lateral
coordinates. Held so, its depth does not move: the run ends with the point where it was
first held, above the optimum by its rays' share (Ladybug's receding points: tight runs
1e-9 relative; a point thrown 1e9 times its distance along one of its rays: vᵀPv 1e5 times
the optimum).

:func:`depth_search` gives each held point its depth anew after the step, given the
step's new image parameters and the point's new lateral position. In inverse depth the
rays of a far point are nearly linear: with C̄ the mean of the point's images' new
centres and a = X − C̄ (X the point after the step), the point C̄ + a/u (u > 0; u = 1 the
step's own, u → 0 the point at infinity in the direction of a) is seen from the centre
C_i along a + u (C̄ − C_i), so each misclosure is r_i(u) ≈ r_i∞ + u c_i to second order in
u ‖C̄ − C_i‖ / ‖a‖. The misclosures at u = 1 and u = ½ give r∞ and c; the model's
minimiser u* (for a robust loss the best of a grid in u, :data:`DEPTH_GRID`) is taken
within [:data:`DEPTH_MIN_U`, :data:`DEPTH_MAX_U`] — a point that the model sends to or
beyond infinity recedes by a factor 1/:data:`DEPTH_MIN_U` per step, where its rays' Σρ
falls by about as much of what remains to the limit, but never beyond the farthest
distance (:data:`DEPTH_FAR_SIZES`, :data:`DEPTH_FAR_SHARE`: past it the rays do not change
within their rounding, and a written result stays readable); one far off comes back by
halves. Of
u ∈ {1, ½, u*} each point keeps the one whose true misclosures give its rays the lowest Σρ,
and moves only when that lowers them by more than :data:`DEPTH_GAIN` of their Σρ (below
it the difference is rounding: a point at the limit is not pushed further from step to
step). The points do not interact given the images, so the trial's Σρ is at most the
step's own. The step's own correction stays its model's and its stopping measure's (the
depth is no unknown of the held step).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...plausibility import ABSURD_M
from ..problem import BundleProblem, BundleState
from ._loss import RobustLoss
from ._tail import ray_misclosures

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: The smallest inverse depth (relative to the step's own, u = 1) a held point is moved
#: to in one step: a point the model sends to or beyond infinity recedes 1000-fold.
DEPTH_MIN_U: float = 1e-3
#: The largest: the model, formed at u = ½ and 1, is not trusted closer than half the
#: distance (a point coming back from far off comes back by halves: longer jumps, where the
#: model allowed them, left small blocks' Huber runs in another basin).
DEPTH_MAX_U: float = 2.0
#: A robust loss's u*: the model's Σρ is compared at this many inverse depths spaced
#: evenly in log u over [DEPTH_MIN_U, DEPTH_MAX_U] and at the least-squares u* (reweighted
#: least squares creeps along u where a redescending loss has rays far beyond its scale).
DEPTH_GRID: int = 48
#: The farthest a held point is moved from its images' mean centre, in sizes of the block
#: (the largest extent of its projection centres): there a baseline of a block's size
#: subtends 1e-9 rad, so its rays are within that of their directions at infinity …
DEPTH_FAR_SIZES: float = 1e9
#: … and never beyond this share of :data:`orientviz.plausibility.ABSURD_M`, so that a
#: written result is read again as coordinates (points found beyond it are not moved out).
DEPTH_FAR_SHARE: float = 1e-2
#: A point moves only when its rays' Σρ falls by more than this fraction of it (~64 ε:
#: a smaller difference is the rounding of the sum).
DEPTH_GAIN: float = 1e-14


def depth_search(
    prob: BundleProblem,
    loss: RobustLoss | None,
    weight: F64,
    st: BundleState,
    dc: F64,
    da: F64,
    dp: F64,
    held: I64,
    images: tuple[F64, F64],
) -> tuple[F64, int, float]:
    """Per held point the depth with the lowest Σρ of its rays (see the module docstring).

    Parameters
    ----------
    prob : BundleProblem
    loss : RobustLoss or None
        The loss of the step's cost (None: least squares, ρ(s) = s).
    weight : ndarray, shape (n, 2)
        The rays' weights of the cost (1/σ, 1/mm); set as the problem's ray weights.
    st : BundleState
        The state the step starts from.
    dc, da, dp : ndarray
        The step's corrections of the images (m, 6), the additional parameters and the
        point unknowns (p_var, 3), m.
    held : ndarray of int
        The held point unknowns.
    images : tuple of ndarray
        (X0, angles) of the step's new image parameters (st.X0 + dc[:, :3], st.angles +
        dc[:, 3:]).

    Returns
    -------
    dp, moved, gain
        The corrections with the held points' depths sought (a copy; ``dp`` itself when
        none moves), the number of points moved, the decrease of Σρ against ``dp``.
    """
    pts = prob.points
    pw = pts.prior_w
    mask = np.zeros(pw.shape[0], dtype=bool)
    mask[held] = True
    mask &= (pw[:, 0] == 0) & (pw[:, 1] == 0) & (pw[:, 2] == 0)  # a prior: not free
    held = np.flatnonzero(mask)
    if not held.size:
        return dp, 0, 0.0
    tg = prob.reduced.tracks
    bp = tg.by_point  # its rows list each point's rays (columns: the tracks' ray order)
    counts = np.diff(bp.indptr)
    n_rays = counts[held]
    rays = bp.indices[np.repeat(mask, counts)]
    obs_rays = rays if tg.in_order else tg.rays[rays]
    starts = np.zeros(held.size, dtype=np.intp)
    np.cumsum(n_rays[:-1], out=starts[1:])
    owner = np.repeat(np.arange(held.size), n_rays)
    X0, angles = images
    centre = np.add.reduceat(X0.take(prob.obs.image[obs_rays], axis=0), starts) / n_rays[:, None]
    a = st.xyz.take(pts.unknown[held], axis=0) + dp[held] - centre
    # the least inverse depth: no farther than the farthest (DEPTH_FAR_SIZES, _SHARE); a
    # point already beyond may only come closer
    size = float(np.max(np.ptp(X0, axis=0))) if X0.shape[0] > 1 else 0.0
    far = ABSURD_M * DEPTH_FAR_SHARE
    if size > 0.0:
        far = min(far, DEPTH_FAR_SIZES * size)
    u_low = np.maximum(np.minimum(np.linalg.norm(a, axis=1) / far, 1.0), DEPTH_MIN_U)
    ap = st.ap + da
    prob.obs.weight[...] = weight

    def at(u: F64) -> F64:  # the rays' positions of each point at inverse depths u (k, h)
        return (centre[None] + a[None] / u[:, :, None]).take(owner, axis=1).reshape(-1, 3)

    def costs(rw: F64) -> F64:  # Σρ per point of misclosures (k·m, 2) → (k, h)
        s = rw[:, 0] * rw[:, 0] + rw[:, 1] * rw[:, 1]
        rho = s if loss is None else loss.rho(s)
        return np.add.reduceat(rho.reshape(-1, rays.size), starts, axis=1)

    u = np.array([[1.0], [0.5]]).repeat(held.size, axis=1)
    rw = ray_misclosures(prob, X0, angles, ap, np.tile(obs_rays, 2), at(u)).reshape(2, -1, 2)
    c = 2.0 * (rw[0] - rw[1])  # r(u) ≈ r∞ + u c
    r_inf = rw[0] - c
    rc = np.sum(r_inf * c, axis=1)
    cc = np.sum(c * c, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):  # the model's least-squares u*
        best = -np.add.reduceat(rc, starts) / np.add.reduceat(cc, starts)
    best = np.clip(np.nan_to_num(best, nan=1.0), u_low, DEPTH_MAX_U)
    if loss is not None:  # a robust loss: the model's Σρ on a grid of u and at u*
        grid = np.concatenate(
            (
                np.maximum(np.geomspace(DEPTH_MIN_U, DEPTH_MAX_U, DEPTH_GRID)[:, None], u_low),
                best[None],
            )
        )
        gu = grid.take(owner, axis=1)[:, :, None]  # (g, k, 1)
        r = r_inf[None] + gu * c[None]
        model = np.add.reduceat(loss.rho(np.sum(r * r, axis=2)), starts, axis=1)
        best = grid[np.argmin(model, axis=0), np.arange(held.size)]
    true = np.empty((3, held.size))
    true[:2] = costs(rw.reshape(-1, 2))
    true[2] = costs(ray_misclosures(prob, X0, angles, ap, obs_rays, at(best[None])))
    true[1, u_low > 0.5] = np.inf  # half the inverse depth: beyond the farthest
    cand = np.array([np.ones(held.size), np.full(held.size, 0.5), best])
    k = np.argmin(np.where(np.isfinite(true), true, np.inf), axis=0)
    pick = np.arange(held.size)
    gain = true[0] - true[k, pick]
    move = gain > DEPTH_GAIN * np.abs(true[0])
    if not move.any():
        return dp, 0, 0.0
    out = dp.copy()
    j = held[move]
    out[j] = (
        centre[move]
        + a[move] / cand[k[move], pick[move], None]
        - st.xyz.take(pts.unknown[j], axis=0)
    )
    return out, int(np.count_nonzero(move)), float(np.sum(gain[move]))
