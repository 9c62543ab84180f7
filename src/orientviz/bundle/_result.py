"""The typed result of a bundle adjustment and its parts.

:class:`BundleResult` (a :class:`~orientviz.block.BlockAdjustment`) with the precision's
per-ray gains (:class:`RayGains`) and image–image cofactors (:class:`ExteriorPairs`);
:class:`RaySubset` is a block's rays re-adjusted in the cleaning's checks. Filled by
:func:`orientviz.bundle.loop._finish.finish_result`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..block import BlockAdjustment
from .model import LensEstimates

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class RayGains:
    """How a bias of each ray moves its own image and point (external reliability).

    K = Q_(·, ray) Jᵀ P½ per image observation: a bias ∇ (mm) of the ray moves its
    image's exterior orientation by K_e P½ ∇ and its point by K_p P½ ∇ (NaN for rays
    not in the adjustment).

    Attributes
    ----------
    exterior : ndarray, shape (n, 6, 2)
        Change of X0 (m), ω φ κ (rad) per σ of the ray's x, y.
    points : ndarray, shape (n, 3, 2)
        Change of X, Y, Z (m) per σ of the ray's x, y.
    """

    exterior: F64
    points: F64


@dataclass(frozen=True)
class ExteriorPairs:
    """Cofactor blocks Q_cc of the image pairs that share a point (2-D tests of check rays).

    Attributes
    ----------
    keys : ndarray of int
        i·m + k for the pairs i ≤ k (sorted).
    blocks : ndarray, shape (pairs, 6, 6)
        Their 6 × 6 cofactor blocks (m², m·rad, rad²).
    """

    keys: NDArray[np.int64]
    blocks: F64


@dataclass(frozen=True)
class RaySubset:
    """A gross-error solver's round: the bundle of the block without the rejected rays.

    Attributes
    ----------
    kept_rays : ndarray of bool, shape (n,)
        Rays of the block that were adjusted.
    kept_points : ndarray of int
        Block index of each point of the adjusted sub-block.
    redundancy : str
        How the redundancy numbers were obtained: ``"exact"`` or ``"local"``.
    adjustment : BundleResult
        The bundle of the sub-block itself.
    """

    kept_rays: NDArray[np.bool_]
    kept_points: NDArray[np.int64]
    redundancy: str
    adjustment: Any


@dataclass
class BundleResult(BlockAdjustment):
    """What :func:`orientviz.bundle.bundle_adjust` returns.

    Besides the fields of :class:`~orientviz.block.BlockAdjustment` (``exterior`` (m, 6),
    ``points`` (p, 3), ``check_points``, ``auxiliary``) and of
    :class:`~orientviz.adjust.result.Adjustment`:

    Attributes
    ----------
    additional : ndarray, shape (q,)
        Additional parameters, group-major (units of the set, e.g. µm); empty without.
    used_obs : ndarray of bool, shape (n,)
        Image observations that entered the adjustment (rays of check points do not).
    solver : str
        Solver of the reduced camera system that was used (``"banded"``, ``"dense"``,
        ``"sparse"``; ``reduced_info["solver_reason"]`` says why it was chosen).
    reduced_info : dict
        Diagnostics of the reduced system (ordering, bandwidths) and, with additional
        parameters, ``"ap_border"``: how each solve of their border went.
    ray_gains : RayGains or None
        With the precision: gains of each ray on its image and point.
    exterior_pairs : ExteriorPairs or None
        With the precision: Q_cc of the image pairs sharing a point.
    redundancy_check : float or None
        Σ of the redundancy numbers (equals the redundancy), with the precision.
    precision_error : str or None
        Why a not converged result carries no precision.
    subset : RaySubset or None
        For the rounds of :func:`orientviz.bundle.bundle_solver`: which rays were adjusted
        (``points`` then holds all block points, dropped ones from their rays).
    camera : LensEstimates or None
        With a :class:`~orientviz.bundle.LensModel`: the cameras' interior orientation
        and lens parameters in physical units, their σ and correlations.
    """

    additional: F64 = field(default_factory=lambda: np.zeros(0))
    used_obs: NDArray[np.bool_] | None = None
    solver: str = ""
    reduced_info: dict[str, Any] = field(default_factory=dict)
    ray_gains: RayGains | None = None
    exterior_pairs: ExteriorPairs | None = None
    redundancy_check: float | None = None
    precision_error: str | None = None
    subset: RaySubset | None = None
    camera: LensEstimates | None = None
