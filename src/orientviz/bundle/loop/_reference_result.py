"""``bundle_adjust(..., solver="reference")``: the textbook iteration's estimates as a
:class:`~orientviz.bundle.BundleResult`.

:mod:`orientviz.bundle.reference` iterates; this adapter only builds the result from
its estimates: the history (one :class:`~orientviz.adjust.result.Iteration` per
iterate, vᵀPv and σ̂0 from the reference), and the residuals, redundancy, check points
and (on request) precision of the estimates by the result code every solver shares.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...adjust.result import Iteration
from ...block import Block
from .._result import BundleResult
from ..problem import BundleProblem, BundleState, PointSetup
from ..reference import reference_bundle
from ._finish import finish_result

#: What ``reduced_info["solver_reason"]`` says for the reference.
REASON = "by the textbook reference iteration (orientviz.bundle.reference): dense Schur complement"


def reference_result(
    block: Block,
    setup: PointSetup,
    *,
    control: str,
    max_iter: int,
    tol: float,
    additional,
    ap_group,
    ap_sigma,
    precision: bool,
    callback: Callable[[Iteration], object] | None,
    history_x: bool | None,
) -> BundleResult:
    """Run :func:`~orientviz.bundle.reference.reference_bundle` and build the result
    (arguments as :func:`orientviz.bundle.bundle_adjust`, after its checks)."""
    sol = reference_bundle(
        block, control=control, additional=additional, ap_group=ap_group, ap_sigma=ap_sigma,
        max_iter=max_iter, tol=tol,
    )  # fmt: skip
    prob = BundleProblem(
        block, setup, additional=additional, ap_group=ap_group, ap_sigma=ap_sigma, solver="dense"
    )
    dof = prob.redundancy

    def s0(cost: float) -> float:
        return float(np.sqrt(cost / dof)) if dof > 0 else float("nan")

    keep_x = block.n_images <= 500 if history_x is None else bool(history_x)
    history = []
    for k, (x, cost) in enumerate(zip(sol.x, sol.cost)):
        dx = None if k == 0 else x - sol.x[k - 1]
        corr = float("nan") if k == 0 else sol.max_correction[k - 1]
        rec = Iteration(k, x if keep_x else np.empty(0), dx if keep_x or k == 0 else np.empty(0),
                        s0(cost), cost, 0.0, corr)  # fmt: skip
        history.append(rec)
        if callback is not None and k > 0:
            callback(rec)
    st = BundleState(sol.X0, sol.angles, sol.xyz, sol.ap)
    rw, Je, Jp = prob.residuals(st, jac=True)
    res = finish_result(
        block, prob, st, rw, Je, Jp, prob.names(), history, sol.converged, sol.reason,
        precision, dof, s0(sol.cost[-1]),
    )  # fmt: skip
    res.solver = "reference"
    res.reduced_info = {"solver_reason": REASON}
    if prob.ap.lens is not None:
        Q = res.cofactor_groups.get("additional") if prob.q else None
        res.camera = prob.ap.lens.estimates(st.ap, Q, res.sigma0)
    return res
