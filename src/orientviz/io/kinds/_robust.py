"""Robust bundle adjustment for ``orientviz solve --robust huber|cauchy``.

An M-estimator by iteratively reweighted least squares: each ray (x, y of one image
point) gets the weight factor w(e) of its standardised residual e = ‖(v_x/σ_x,
v_y/σ_y)‖ from the previous adjustment, i.e. its σ becomes σ/√w; the bundle is repeated
from the previous solution until no factor changes by more than ``WEIGHT_TOL``.

* Huber: w = 1 for e ≤ k, k/e beyond — the influence of a large residual is bounded.
* Cauchy: w = 1 / (1 + (e/k)²) — the influence redescends, gross errors lose almost all
  weight (not convex: it needs the good start the least-squares solution gives).

k is the scale in units of the observations' σ (defaults: 1.345 and 2.385, the 95 %
efficiency constants under normal errors). The final adjustment keeps the last weights:
its σ̂0, σ and normalised residuals refer to the down-weighted σ; the note lists the rays
that lost most weight, by image and point id.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...block import Block
from ...errors import InputError

#: ``options.robust`` / ``--robust``.
LOSSES = ("none", "huber", "cauchy")
#: Default scale k (units of σ) per loss.
DEFAULT_SCALE = {"huber": 1.345, "cauchy": 2.385}
#: Stop reweighting when no weight factor changes by more than this.
WEIGHT_TOL: float = 5e-3
#: At most this many reweighted adjustments.
MAX_ROUNDS: int = 50


def weight_factors(e: np.ndarray, loss: str, k: float) -> np.ndarray:
    """Weight factors w(e) of standardised residuals ``e`` ≥ 0 (dimensionless)."""
    e = np.nan_to_num(np.abs(np.asarray(e, float)), nan=0.0)
    if loss == "huber":
        return np.where(e <= k, 1.0, k / np.maximum(e, 1e-300))
    if loss == "cauchy":
        return 1.0 / (1.0 + (e / k) ** 2)
    raise InputError(f"robust must be one of {', '.join(LOSSES)}, got {loss!r}")


@dataclass
class RobustRun:
    """What the reweighting did: the loss, scale, rounds, final weight per ray, a note."""

    loss: str
    scale: float
    rounds: int
    weights: np.ndarray
    settled: bool

    def note(self, block: Block, shown: int = 8) -> str:
        """One line for the report: the loss and the rays that lost most weight (ids)."""
        low = np.flatnonzero(self.weights < 0.5)
        low = low[np.argsort(self.weights[low])]
        obs = block.observations
        rays = ", ".join(
            f"{block.images.ids[obs.image[i]]}/{block.points.ids[obs.point[i]]} "
            f"(w = {self.weights[i]:.2g})"
            for i in low[:shown]
        )
        more = f" and {low.size - shown} more" if low.size > shown else ""
        state = "" if self.settled else f" (weights still changing after {self.rounds} rounds)"
        return (
            f"robust adjustment ({self.loss}, scale {self.scale:g} σ): {self.rounds} reweighted "
            f"adjustments{state}; σ0, σ and w refer to the down-weighted σ; "
            + (
                f"{low.size} ray(s) with weight < 0.5: {rays}{more}"
                if low.size
                else "no ray lost half its weight"
            )
        )


def robust_bundle(block: Block, loss: str, scale: float | None, solve) -> tuple[object, RobustRun]:
    """Adjust ``block`` by IRLS with ``solve(block) -> BundleResult`` (the plain bundle).

    Parameters
    ----------
    block : Block
        Approximate values and observations (σ in mm).
    loss : {"huber", "cauchy"}
    scale : float or None
        k in units of σ (None: :data:`DEFAULT_SCALE`).
    solve : callable
        The bundle with the problem's options.

    Returns
    -------
    (BundleResult, RobustRun)
        The last adjustment (weights applied) and what the reweighting did.
    """
    if loss not in DEFAULT_SCALE:
        raise InputError(f"robust must be one of {', '.join(LOSSES)}, got {loss!r}")
    k = DEFAULT_SCALE[loss] if scale is None else float(scale)
    if not (np.isfinite(k) and k > 0):
        raise InputError(f"robust_scale must be a positive number, got {scale!r}")
    sigma0 = block.observations.sigma.copy()
    n = block.n_observations
    w = np.ones(n)
    work = block.copy()
    adj = solve(work)
    used = np.ones(n, bool) if adj.used_obs is None else np.asarray(adj.used_obs, bool)
    rounds, settled = 1, False
    while rounds < MAX_ROUNDS:
        v = adj.residuals[: 2 * n].reshape(n, 2)
        e = np.hypot(v[:, 0] / sigma0[:, 0], v[:, 1] / sigma0[:, 1])
        new = np.where(np.isfinite(e) & used, weight_factors(e, loss, k), 1.0)
        change = float(np.max(np.abs(new - w), initial=0.0))
        w = new
        if change < WEIGHT_TOL:
            settled = True
            break
        work = work.copy()
        work.observations.sigma = sigma0 / np.sqrt(w)[:, None]
        if adj.converged and adj.exterior is not None:  # warm start
            work.images.X0 = adj.exterior[:, :3].copy()
            work.images.angles = adj.exterior[:, 3:].copy()
            free = np.isfinite(adj.points).all(axis=1)
            work.points.xyz[free] = adj.points[free]
        adj = solve(work)
        rounds += 1
    return adj, RobustRun(loss, k, rounds, w, settled)
