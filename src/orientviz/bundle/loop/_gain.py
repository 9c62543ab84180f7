"""The decrease of vᵀPv a bundle step's linear model predicts (the step's gain ratio).

A Levenberg-Marquardt step δ from an iterate x is chosen on the linear model of the
misclosures, r(x + δ) ≈ r − J·δ (r = P½(l − f), J = P½ ∂f/∂x). The model predicts the
decrease

    vᵀPv(x) − ‖r − J·δ‖² − (pseudo-observations at x + δ) = 2 rᵀJδ − ‖Jδ‖² + Δ(pseudo-obs.)

— Ceres's ``model_cost_change`` of the undamped model (×2: vᵀPv, not ½Σr²). The ratio of
the realised decrease to it is the step's gain ratio ρ. A step with ρ near 1 is one the
model describes; one that realises a small fraction of its prediction (ρ < 1/4: a poor
step in the trust-region convention, Moré 1978, Nocedal & Wright 2006, Alg. 4.1) says that
the model is poor along it — its small decrease says nothing about convergence. The
bundle forms the prediction only when a least-squares step's decrease would meet the
stopping rule's ``ftol`` (:meth:`~orientviz.bundle.loop.BundleSteps.accepted`): one pass
over the rays per run, usually.

What it is for: a point whose rays diverge (their least-squares intersection lies behind
the cameras) recedes along them in every step while vᵀPv falls ∝ 1/distance towards its
infimum at infinity; its step's model (quadratic in the point's coordinates) is poor, and a
damped step that barely lowers vᵀPv would otherwise end the run early.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..problem import BundleProblem, BundleState

F64 = NDArray[np.float64]

#: A step that realises less than this fraction of its model's predicted decrease of vᵀPv
#: is a poor step (gain ratio ρ < 1/4, the trust-region convention): its decrease may not
#: end the run by ``ftol`` (:meth:`~orientviz.bundle.loop.BundleSteps.may_stop`).
POOR_GAIN: float = 0.25


def predicted_decrease(
    prob: BundleProblem,
    st: BundleState,
    lin: tuple[F64, F64, F64],
    step: tuple[F64, F64, F64],
    design: F64 | None,
    local: bool = False,
) -> float:
    """The decrease of vᵀPv that the linear model at ``st`` predicts for a step.

    Parameters
    ----------
    prob : BundleProblem
        The problem (its rays' images, point unknowns and weights 1/σ, 1/mm).
    st : BundleState
        The iterate the step starts from.
    lin : (rw, Je, Jp)
        The linearisation at ``st``: misclosures P½(l − f) (n, 2), and the unweighted
        derivatives of the image coordinates by each ray's image's six exterior unknowns
        (n, 2, 6) and by its point (n, 2, 3), mm per m and per rad.
    step : (dc, dp, da)
        The step: exterior (m, 6), point unknowns (p, 3), additional parameters (q,).
    design : ndarray, shape (2n, q), or None
        The additional parameters' design at ``st`` (mm per unit; a sparse matrix), None
        without them.
    local : bool
        ``dc``'s angles are rotations of the image frames (``Je`` by them).

    Returns
    -------
    float
        vᵀPv(st) minus the model's vᵀPv at st + step (dimensionless, units of σ²).
    """
    rw, Je, Jp = lin
    dc, dp, da = step
    obs = prob.obs
    # J·δ per ray (mm): the exterior part, the point part (rays of point unknowns), A·a
    Jd = np.einsum("nij,nj->ni", Je, np.take(dc, obs.image, axis=0))
    var = obs.column >= 0
    Jd[var] += np.einsum("nij,nj->ni", Jp[var], np.take(dp, obs.column[var], axis=0))
    if design is not None and prob.q:
        Jd += (design @ da[: prob.q]).reshape(-1, 2)
    Jd *= obs.weight
    rays = 2.0 * float(np.sum(rw * Jd)) - float(np.sum(Jd * Jd))
    # the pseudo-observations (held coordinates, priors; linear in x: the model is exact)
    # and auxiliary rows by their change
    new = prob.apply(st, dc, dp, da, local=local)
    pseudo = prob.cost(st, rw[:0]) - prob.cost(new, rw[:0])
    return rays + pseudo
