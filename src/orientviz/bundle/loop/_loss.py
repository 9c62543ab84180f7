"""Robust losses of the bundle: ρ of a ray's squared standardised misclosure.

A ray (x, y of one image point) with weighted misclosure r = P½(l − f) has the squared
norm s = ‖r‖² = (v_x/σ_x)² + (v_y/σ_y)² (dimensionless). A robust bundle minimises
Σ ρ(s) over the rays (plus the pseudo-observations' vᵀPv) instead of Σ s; with scale a
(units of σ) and b = a²:

* ``"huber"``: ρ = s for s ≤ b, 2a√s − b beyond (the influence of a large misclosure
  is bounded);
* ``"cauchy"``: ρ = b·ln(1 + s/b) (the influence redescends: gross errors lose almost
  all weight; not convex, it needs a good start);
* ``"soft_l1"``: ρ = 2b(√(1 + s/b) − 1) (a smooth Huber).

These are Ceres Solver's ``HuberLoss(a)``, ``CauchyLoss(a)`` and ``SoftLOneLoss(a)`` on a
residual block of one ray (Ceres's cost is ½ Σ ρ), and scipy's ``least_squares`` losses
with ``f_scale = a`` on the ray's norm. All three are concave in s (ρ″ ≤ 0), and the
model of ρ at an iterate is the ray's rows scaled by √ρ′(s) — the model Ceres uses for
such losses (its second-order correction of Triggs et al. 2000, "Bundle adjustment — a
modern synthesis", applies only where ρ″ > 0). ρ is concave, ρ(s) ≤ ρ(s₀) +
ρ′(s₀)(s − s₀): lowering the reweighted Σ ρ′(s₀)·s lowers Σ ρ (iteratively reweighted
least squares inside each step, sound far from the solution too), and the model has the
gradient of Σ ρ, so a step that leaves the iterate
unchanged is a stationary point of the robust cost; near it the convergence is linear,
the faster the fewer rays are down-weighted. A second-order model, curvature
ρ′ + 2sρ″ along each misclosure, serves only in a convex loss's tail
(:data:`orientviz.bundle.loop._steps.ROBUST_TAIL_FLOOR`): from start values where most
rays lie beyond the scale its steps decreased Σ ρ by a fraction of what these do.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ...errors import InputError
from .._options import LOSSES

F64 = NDArray[np.float64]

#: Default scale a per loss (units of σ): 95 % efficiency under normal errors of one
#: coordinate (Huber 1.345, Cauchy 2.385; soft-L1 as Huber).
DEFAULT_SCALE: dict[str, float] = {"huber": 1.345, "cauchy": 2.385, "soft_l1": 1.345}


@dataclass(frozen=True)
class RobustLoss:
    """A robust loss ρ(s) of a ray's squared standardised misclosure s (see the module).

    Attributes
    ----------
    kind : {"huber", "cauchy", "soft_l1"}
    scale : float
        a, in units of the observations' σ (dimensionless, > 0).
    """

    kind: str
    scale: float

    def __post_init__(self) -> None:
        if self.kind not in LOSSES[1:]:
            raise InputError(f"loss must be one of {', '.join(LOSSES)}, got {self.kind!r}")
        if not (np.isfinite(self.scale) and self.scale > 0):
            raise InputError(f"the loss's scale must be a positive number, got {self.scale!r}")

    @classmethod
    def named(cls, kind: str, scale: float | None = None) -> RobustLoss | None:
        """The loss ``kind`` with ``scale`` (None: :data:`DEFAULT_SCALE`); None for "none"."""
        if kind == "none":
            return None
        if kind not in DEFAULT_SCALE:
            raise InputError(f"loss must be one of {', '.join(LOSSES)}, got {kind!r}")
        return cls(kind, DEFAULT_SCALE[kind] if scale is None else float(scale))

    @property
    def redescending(self) -> bool:
        """Whether the influence of a large misclosure falls off again (Cauchy): ρ is then
        not convex in the misclosure, and the start decides the minimum found."""
        return self.kind == "cauchy"

    def __call__(self, s: F64) -> tuple[F64, F64]:
        """ρ(s) and ρ′(s) for squared norms ``s`` ≥ 0 (dimensionless)."""
        s = np.asarray(s, float)
        b = self.scale * self.scale
        if self.kind == "huber":
            out = s > b
            root = np.sqrt(np.where(out, s, 1.0))
            return np.where(out, 2.0 * self.scale * root - b, s), np.where(
                out, self.scale / root, 1.0
            )
        if self.kind == "cauchy":
            return b * np.log1p(s / b), 1.0 / (1.0 + s / b)
        root = np.sqrt(1.0 + s / b)  # soft_l1
        return 2.0 * b * (root - 1.0), 1.0 / root

    def rho(self, s: F64) -> F64:
        """ρ(s) alone (the values of ``self(s)[0]``)."""
        s = np.asarray(s, float)
        b = self.scale * self.scale
        if self.kind == "huber":
            out = s > b
            return np.where(out, 2.0 * self.scale * np.sqrt(np.where(out, s, 1.0)) - b, s)
        if self.kind == "cauchy":
            return b * np.log1p(s / b)
        return 2.0 * b * (np.sqrt(1.0 + s / b) - 1.0)

    def newton_terms(self, s: F64) -> tuple[F64, F64]:
        """ρ′(s) and (ρ′ + 2sρ″)/ρ′ together (the values of ``self(s)[1]`` and
        :meth:`along`)."""
        s = np.asarray(s, float)
        b = self.scale * self.scale
        if self.kind == "huber":
            out = s > b
            return np.where(out, self.scale / np.sqrt(np.where(out, s, 1.0)), 1.0), np.where(
                out, 0.0, 1.0
            )
        if self.kind == "soft_l1":
            t = 1.0 + s / b
            return 1.0 / np.sqrt(t), 1.0 / t
        return self(s)[1], self.along(s)

    def along(self, s: F64) -> F64:
        """(ρ′ + 2sρ″)/ρ′ per squared norm ``s`` (dimensionless, ≥ 0): Σρ's Gauss-Newton
        curvature along a ray's misclosure over the reweighted model's ρ′ (across the
        misclosure both are ρ′). Huber 1 within the scale and 0 beyond it, soft-L1
        1/(1 + s/b), Cauchy (1 − s/b)/(1 + s/b) clipped at 0 (b = a²)."""
        s = np.asarray(s, float)
        b = self.scale * self.scale
        if self.kind == "huber":
            return np.where(s > b, 0.0, 1.0)
        if self.kind == "soft_l1":
            return 1.0 / (1.0 + s / b)
        return np.maximum((1.0 - s / b) / (1.0 + s / b), 0.0)

    def weights(self, s: F64) -> F64:
        """ρ′(s): the weight factor of each ray (its σ becomes σ/√ρ′)."""
        return self(s)[1]
