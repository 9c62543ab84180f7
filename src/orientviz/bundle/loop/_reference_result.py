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
from .._options import BundleOptions
from .._result import BundleResult
from ..problem import BundleProblem, BundleState, PointSetup
from ..reference import reference_bundle
from ._finish import RunEnd, finish_result

#: What ``reduced_info["solver_reason"]`` says for the reference.
REASON = "by the textbook reference iteration (orientviz.bundle.reference): dense Schur complement"


def reference_result(
    block: Block,
    setup: PointSetup,
    *,
    control: str,
    additional,
    ap_group,
    ap_sigma,
    precision: bool,
    callback: Callable[[Iteration], object] | None,
    options: BundleOptions,
) -> BundleResult:
    """Run :func:`~orientviz.bundle.reference.reference_bundle` and build the result
    (arguments as :func:`orientviz.bundle.bundle_adjust`, after its checks; of
    ``options`` the reference reads ``max_iter``, ``tol``, ``history_x``,
    ``history_x_limit``)."""
    sol = reference_bundle(
        block, control=control, additional=additional, ap_group=ap_group, ap_sigma=ap_sigma,
        max_iter=options.max_iter, tol=options.tol,
    )  # fmt: skip
    prob = BundleProblem(
        block, setup, additional=additional, ap_group=ap_group, ap_sigma=ap_sigma,
        options=options.replace(solver="dense"),
    )  # fmt: skip
    dof = prob.redundancy

    def s0(cost: float) -> float:
        return float(np.sqrt(cost / dof)) if dof > 0 else float("nan")

    hx = options.history_x
    keep_x = block.n_images <= options.history_x_limit if hx is None else bool(hx)
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
    end = RunEnd(st, rw, Je, Jp, sol.cost[-1], history, sol.converged, sol.reason, precision)
    res = finish_result(prob, end)
    res.solver = "reference"
    res.reduced_info = {"solver_reason": REASON}
    return res
