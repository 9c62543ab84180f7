"""Robust bundle adjustment for ``orientviz solve --robust huber|cauchy|soft_l1``.

The file's ``options.robust`` and ``options.robust_scale`` become the bundle's
``BundleOptions(loss=…, loss_scale=…)``: the loss ρ of each ray's squared standardised
misclosure is minimised inside the Levenberg-Marquardt loop, each step's rays weighted
by √ρ′ (:mod:`orientviz.bundle.loop._loss`; Ceres's ``HuberLoss``, ``CauchyLoss``,
``SoftLOneLoss`` with the same scale). The result refers to the down-weighted σ/√w of
the last iterate (w = ρ′); the note lists the rays that lost most weight, by image and
point id.
"""

from __future__ import annotations

import numpy as np

from ...block import Block
from ...bundle import BundleResult
from ...bundle.loop import RobustLoss


def ray_weights(block: Block, adj: BundleResult) -> np.ndarray:
    """Weight factor w of each image observation at the solution (σ/σ_adjusted)², 1 for
    rays not adjusted (dimensionless)."""
    n = block.n_observations
    s_adj = adj.sigma_obs[: 2 * n].reshape(n, 2)[:, 0]
    w = (block.observations.sigma[:, 0] / s_adj) ** 2
    return np.where(np.isfinite(w), w, 1.0)


def robust_note(block: Block, adj: BundleResult, loss: RobustLoss, shown: int = 8) -> str:
    """One line for the report: the loss, its cost Σρ and the rays that lost most weight."""
    w = ray_weights(block, adj)
    low = np.flatnonzero(w < 0.5)
    low = low[np.argsort(w[low])]
    obs = block.observations
    rays = ", ".join(
        f"{block.images.ids[obs.image[i]]}/{block.points.ids[obs.point[i]]} (w = {w[i]:.2g})"
        for i in low[:shown]
    )
    more = f" and {low.size - shown} more" if low.size > shown else ""
    return (
        f"robust adjustment ({loss.kind}, scale {loss.scale:g} σ): Σρ = {adj.history[-1].cost:.8g} in "
        f"{len(adj.history) - 1} iterations; σ0, σ and w refer to the down-weighted σ/√w; "
        + (
            f"{low.size} ray(s) with weight < 0.5: {rays}{more}"
            if low.size
            else "no ray lost half its weight"
        )
    )
